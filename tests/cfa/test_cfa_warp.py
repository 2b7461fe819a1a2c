"""A lens correction's radial warp moves the mosaic: processing, judged block by block, and a paste still found."""

import numpy as np
import pytest
from PIL import Image

from forensics_core import PROCESSING_KEY, DetectorFinding, RadialResampling, Status, load_evidence
from forensics_plugins.cfa import synth
from forensics_plugins.cfa.detector import ColourFilterArray, analyse
from forensics_plugins.cfa.spec import DEFAULT_PARAMS, JPEG_GRID, SPEC
from forensics_plugins.cfa.warp import fitted

#: A mild correction with an editor's zoom: no shift within about 0.55 of the half diagonal, then rings of 1 and 2 px.
WARP = RadialResampling(6.0, -1.0)
SIZE = (768, 1024)
PASTE = (slice(304, 464), slice(432, 592))


def _nearest(rgb: np.ndarray, warp: RadialResampling) -> np.ndarray:
    """The photo resampled by ``warp`` with nearest-neighbour interpolation, as an editor's lens correction does."""
    h, w = rgb.shape[:2]
    y, x = np.mgrid[0:h, 0:w]
    dy, dx = warp.displacement(y, x, (h, w))
    return rgb[np.clip(np.rint(y - dy).astype(int), 0, h - 1), np.clip(np.rint(x - dx).astype(int), 0, w - 1)]


def _corrected_and_pasted(seed: int, warp: RadialResampling) -> tuple[np.ndarray, np.ndarray]:
    """A photo corrected by ``warp``, and the same with a piece of another mosaic pasted in after the correction."""
    host, donor = synth.make_pair(seed, SIZE, algorithm="bilinear", shift=(0, 1), fraction=0.2)
    corrected = _nearest(host.rgb, warp)
    pasted = corrected.copy()
    pasted[PASTE] = donor.rgb[PASTE]
    return corrected, pasted


@pytest.fixture(scope="module")
def photos():
    return _corrected_and_pasted(7, WARP)


def _jpeg_grid_finding(details: dict) -> DetectorFinding:
    return DetectorFinding(name=JPEG_GRID, version="test", plugin="test", status=Status.OK, summary="", score=None,
                           p_value=None, nfa=1.0, details=details, parameters={}, elapsed_s=0.0)


def test_the_rings_a_correction_leaves_are_another_mosaic_to_a_scan_against_one_phase(photos):
    from forensics_plugins.cfa.content_null import null_rates
    from forensics_plugins.cfa.regions import Question, scan
    from forensics_plugins.cfa.residuals import block_features
    from forensics_plugins.cfa.votes import phase_votes

    p = DEFAULT_PARAMS
    feats = block_features(photos[0], 16, 255.0, p["log_offset"])
    usable = (feats.clipped <= p["max_clipped_fraction"]) & (feats.activity >= p["min_activity"])
    votes = phase_votes(feats.features, feats.colour, usable, p["shrinkage"], p["colour_ridge"])
    voting, disagree = usable & (votes.t_diag != 0), votes.t_diag < 0
    null = null_rates(disagree, voting, np.stack([feats.colour, feats.green], axis=2))
    rings = scan([Question("diagonal", disagree, voting, null)], p["nfa_threshold"])
    # Which is why the detector asks each block about the phase the warp gave it (from jpeg_grid or its own search).
    assert rings.regions and rings.min_log10_nfa < -6


def test_with_the_warp_the_corrected_photo_is_processing_and_no_region_departs(photos):
    result = analyse(photos[0], DEFAULT_PARAMS, WARP)
    assert result.status is Status.OK
    assert result.details["regions"] == [] and result.nfa == 1.0
    processing = result.details[PROCESSING_KEY]
    assert processing["kind"] == "radial resampling"
    assert processing["mosaic"]["log10_p"] < -100
    assert "lens correction" in result.summary and "processing" in result.headline


def test_a_piece_pasted_into_the_corrected_photo_is_still_found(photos):
    result = analyse(photos[1], DEFAULT_PARAMS, WARP)
    assert result.status is Status.OK and result.nfa < 1e-3
    x0, y0, x1, y1 = result.details["regions"][0]["bbox_px"]
    truth = np.zeros(SIZE, bool)
    truth[PASTE] = True
    found = np.zeros(SIZE, bool)
    found[y0:y1, x0:x1] = True
    assert (found & truth).sum() > 0.5 * truth.sum()


def test_the_profile_is_refitted_to_the_mosaic(photos):
    from forensics_plugins.cfa.residuals import block_features
    from forensics_plugins.cfa.votes import phase_votes

    p = DEFAULT_PARAMS
    feats = block_features(photos[0], 16, 255.0, p["log_offset"])
    usable = (feats.clipped <= p["max_clipped_fraction"]) & (feats.activity >= p["min_activity"])
    votes = phase_votes(feats.features, feats.colour, usable, p["shrinkage"], p["colour_ridge"])
    # A profile 5 % off, as one fitted to JPEG grid shifts modulo 8 can be, is brought back to the truth.
    refit = fitted(RadialResampling(6.3, -1.05), votes.t_diag, usable & (votes.t_diag != 0), 16, SIZE)
    assert abs(refit.a - 6.0) < 0.15 and abs(refit.b + 1.0) < 0.05


def test_the_detector_reads_the_warp_from_jpeg_grids_finding(photos, tmp_path):
    assert JPEG_GRID in SPEC.uses
    prior = {JPEG_GRID: _jpeg_grid_finding({PROCESSING_KEY: {
        "kind": "radial resampling", "description": "resampled", "radial": WARP.to_details()}})}
    Image.fromarray(photos[0]).save(tmp_path / "corrected.png")
    evidence = load_evidence(tmp_path / "corrected.png")
    with_warp = ColourFilterArray().analyze(evidence, DEFAULT_PARAMS, prior=prior)
    assert with_warp.details["regions"] == [] and PROCESSING_KEY in with_warp.details
    assert with_warp.details[PROCESSING_KEY]["mosaic"]["warp_from"] == "jpeg_grid"
    # Without it, the mosaic's own rings propose the warp (one term; the zoom refitted within the tolerance).
    without = ColourFilterArray().analyze(evidence, DEFAULT_PARAMS, prior={})
    assert without.details[PROCESSING_KEY]["mosaic"]["warp_from"] == "the mosaic itself"


@pytest.mark.parametrize("details", [
    {},
    {PROCESSING_KEY: {"kind": "recompression", "description": "saved again"}},
    {PROCESSING_KEY: {"kind": "radial resampling", "description": "resampled", "radial": {"profile_terms_px": [1]}}},
    {PROCESSING_KEY: {"kind": "radial resampling", "description": "resampled",
                      "radial": {"profile_terms_px": [1.0, float("nan")]}}},
    {PROCESSING_KEY: {"kind": "radial resampling", "description": "resampled",
                      "radial": {"profile_terms_px": [True, 1.0]}}},
])
def test_an_incomplete_warp_record_is_no_warp(details):
    assert RadialResampling.from_finding(_jpeg_grid_finding(details)) is None
    assert RadialResampling.from_finding(None) is None


def test_the_warp_moves_content_along_its_radius():
    dy, dx = RadialResampling(10.0, 0.0).displacement(np.array([0.0]), np.array([0.0]), (101, 101))
    # The corner is at the half diagonal: D(R) = a, pointing outwards (up and left of the centre).
    assert np.allclose([dy[0], dx[0]], [-10 / np.sqrt(2), -10 / np.sqrt(2)])


#: A correction that keeps the frame's scale at the centre (cv2.undistort's default, no zoom): one term only.
UNZOOMED = RadialResampling(12.0, 0.0)


@pytest.fixture(scope="module")
def unzoomed():
    return _corrected_and_pasted(11, UNZOOMED)


def test_without_jpeg_grids_warp_the_mosaic_itself_shows_a_one_term_correction(unzoomed):
    # jpeg_grid establishes no warp where the first grid did not survive; the rings are the mosaic's own evidence.
    result = analyse(unzoomed[0], DEFAULT_PARAMS)
    assert result.status is Status.OK and result.details["regions"] == []
    mosaic = result.details[PROCESSING_KEY]["mosaic"]
    assert mosaic["warp_from"] == "the mosaic itself" and mosaic["log10_p"] < -100
    # Its size: D and -D round to the same parities, so the direction is not shown.
    assert abs(mosaic["profile_terms_px"][0] - 12.0) < 1.0 and abs(mosaic["profile_terms_px"][1]) < 0.6
    assert "its own phases show" in result.summary


def test_a_piece_pasted_into_a_correction_the_mosaic_shows_is_still_found(unzoomed):
    result = analyse(unzoomed[1], DEFAULT_PARAMS)
    assert result.status is Status.OK and result.nfa < 1e-3
    x0, y0, x1, y1 = result.details["regions"][0]["bbox_px"]
    found = np.zeros(SIZE, bool)
    found[y0:y1, x0:x1] = True
    assert found[PASTE].mean() > 0.5
