"""copy_move on photos made here: clones shifted, rotated and scaled, and scenes that repeat themselves."""

import io

import cv2
import numpy as np
from scipy import ndimage
import pytest
from PIL import Image

from forensics_core import Status, analyze, load_evidence
from forensics_plugins.copy_move.detector import analyse, regions_mask
from forensics_plugins.copy_move.spec import DEFAULT_PARAMS
from forensics_plugins.copy_move.synth import clone, encode, scene, synthetic_cases


def _luma(data):
    return np.asarray(Image.open(io.BytesIO(data)).convert("L"), dtype=np.float64) / 255.0


@pytest.fixture(scope="module")
def results():
    out = []
    for case in synthetic_cases(11, 9):
        luma = _luma(case.data)
        out.append((case, analyse(luma, DEFAULT_PARAMS)))
    return out


def _peak(result):
    """The best candidate's grain peak; 0 when no candidate copy could be compared (score 0)."""
    return result.details.get("grain_peak") or 0.0


def test_clones_share_their_fine_grain_and_repetitive_scenes_do_not(results):
    clones = [_peak(r) for c, r in results if c.spliced]
    originals = [_peak(r) for c, r in results if not c.spliced]
    print(f"\nclones {np.round(clones, 2)}\noriginals {np.round(originals, 2)}")
    assert all(r.status is Status.OK and r.p_value is None and r.nfa is None for _, r in results)
    # Shifted and rotated copies keep a grain peak; a copy enlarged and then saved at JPEG quality 85 keeps
    # too little of its grain to stand out from its structure and is missed (a peak near 0), never the reverse.
    kinds = [c.conditions["kind"] for c, _ in results if c.spliced]
    assert all(s > 0.1 for s, kind in zip(clones, kinds) if kind != "copy_scale")
    assert max(originals) < 0.05


def test_the_transform_and_the_copy_are_recovered(results):
    for case, r in results:
        if not case.spliced or r.details["best"] is None:
            continue
        best = next(h for h in r.details["hypotheses"] if h["id"] == r.details["best"])
        assert best["found_by"] == "keypoints" and best["matches_log10_nfa"] < -5
        kind = case.conditions["kind"]
        if kind == "copy_translation":
            assert best["scale"] == pytest.approx(1.0, abs=0.01) and abs(best["rotation_deg"]) < 1.0
        elif kind == "copy_rotation":
            assert 9.0 <= abs(best["rotation_deg"]) <= 41.0
        else:
            assert abs(np.log(best["scale"])) > np.log(1.05)
        mask = regions_mask(r.details, case.mask.shape)
        # The mask covers the copy and its source. A shifted copy keeps its grain exactly, so most of it is
        # found; rotation weakens the grain and only part of the copy has a grain peak of 0.2 or more. The
        # enlarged copies saved at quality 85 have almost none (see above): their transform is what is found.
        covered = (mask & case.mask).sum() / case.mask.sum()
        if kind != "copy_scale":
            assert covered >= (0.3 if kind == "copy_translation" else 0.03)


def test_identical_design_with_independent_grain_is_not_a_copy():
    """A row of windows of one design, each with its own fine texture and noise: keypoints may match, grain must not."""
    rng = np.random.default_rng(5)
    img = scene(rng, (600, 800))
    r = analyse(_luma(encode(img, 92)), DEFAULT_PARAMS)
    assert _peak(r) < 0.1


def test_a_searched_photo_without_a_candidate_scores_zero():
    """No candidate at all is the lowest score, not a decline: the calibrated LR weighs it like a peak of 0."""
    rng = np.random.default_rng(3)
    texture = ndimage.gaussian_filter(rng.random((400, 600)), 1.5)
    r = analyse((texture - texture.min()) / np.ptp(texture), DEFAULT_PARAMS)
    assert r.status is Status.OK and r.details["best"] is None and r.score == 0.0, r.summary


def test_a_flat_photo_is_inconclusive_not_clean():
    flat = np.full((400, 600), 0.5) + np.random.default_rng(0).normal(0, 0.002, (400, 600))
    r = analyse(flat, DEFAULT_PARAMS)
    assert r.status is Status.INCONCLUSIVE and "keypoints" in r.summary and r.score is None


def test_same_photo_same_findings():
    rng = np.random.default_rng(8)
    cloned, _ = clone(scene(rng, (480, 640)), rng, "rotation")
    luma = _luma(encode(cloned, 90))
    assert analyse(luma, DEFAULT_PARAMS).details["hypotheses"] == analyse(luma, DEFAULT_PARAMS).details["hypotheses"]


def test_the_detector_is_advisory_to_the_triage_rule(tmp_path):
    rng = np.random.default_rng(9)
    cloned, _ = clone(scene(rng, (480, 640)), rng, "translation")
    path = tmp_path / "cloned.jpg"
    path.write_bytes(encode(cloned, 90))
    findings = analyze(path, ["copy_move"], isolation="inline")
    (finding,) = findings.detectors
    assert finding.status is Status.OK and finding.details["grain_peak"] > 0.2
    assert [c.role.value for c in findings.verdict.contributions] == ["advisory"]
    assert findings.verdict.label.value == "inconclusive"


def test_through_the_entry_point_with_its_report_section(tmp_path):
    from forensics_core.analysis import Options, analyze_evidence
    from forensics_core.plugins import PluginHost
    from forensics_core.report.plugin_sections import section_for

    host = PluginHost.from_entry_points(allow=["copy_move"])
    assert host.detectors["copy_move"].spec.calibrated_on == "score"
    rng = np.random.default_rng(12)
    cloned, _ = clone(scene(rng, (480, 640)), rng, "translation")
    path = tmp_path / "cloned.jpg"
    path.write_bytes(encode(cloned, 90))
    ev = load_evidence(path)
    (finding,) = analyze_evidence(ev, host, Options(detectors=["copy_move"], isolation="process")).detectors
    assert finding.status is Status.OK and finding.details["grain_peak"] > 0.2, finding.error or finding.summary
    section = section_for(host, finding, ev)
    assert section.failure is None
    body = str(section.body)
    for text in ("Candidate copies", "fine grain", "Strength and limits", "Amerini", "printed"):
        assert text in body, text
    assert [f.key for f in section.figures] == ["overlay", "regions"] and all(f.used for f in section.figures)
    assert "two regions of the best candidate, enlarged" in body


def test_the_matches_number_of_false_alarms_falls_as_more_pairs_agree():
    from forensics_plugins.copy_move.transforms import log10_nfa

    area = 600 * 800
    assert log10_nfa(200, 5, 3.0, area) > log10_nfa(200, 10, 3.0, area) > log10_nfa(200, 40, 3.0, area)
    # A handful of pairs out of thousands, all within a pixel tolerance of a large one, is chance.
    assert log10_nfa(5000, 5, 50.0, area) > 0


@pytest.mark.parametrize("angle, factor", [(20.0, 1.0), (0.0, 0.8)])
def test_the_grain_is_compared_the_way_the_copy_was_made(angle, factor):
    """Warping the source onto its copy repeats the copy's resampling; the reverse does not.

    Measured on 4 scenes: a copy rotated by 20° has a grain peak of 0.36-0.39 compared from its source and
    0.20-0.25 the other way round; one shrunk to 0.8, 0.40-0.44 against 0.14-0.16.
    """
    from forensics_plugins.copy_move.identity import best_alignment, identity, residual
    from forensics_plugins.copy_move.transforms import Hypothesis

    img = scene(np.random.default_rng(0), (600, 800))
    side, (sx, sy), (tx, ty) = 180, (60, 300), (450, 60)
    m = cv2.getRotationMatrix2D((sx + side / 2, sy + side / 2), angle, factor)
    m[:, 2] += (tx - sx, ty - sy)
    moved = cv2.warpAffine(img.astype(np.float32), m, (800, 600), flags=cv2.INTER_LINEAR)
    disc = np.zeros((600, 800), np.uint8)
    cv2.circle(disc, (tx + side // 2, ty + side // 2), side // 2, 1, -1)
    img[disc.astype(bool)] = moved[disc.astype(bool)]
    gray = np.asarray(Image.open(io.BytesIO(encode(img, 95))), dtype=np.float32)
    grain = residual(gray)
    ys, xs = np.nonzero(disc)
    copy = np.column_stack([xs, ys]).astype(np.float32)[::50]
    back = cv2.invertAffineTransform(m)
    made = Hypothesis(m, copy @ back[:, :2].T + back[:, 2], copy)
    forward, backward = (identity(gray, grain, h, 16, 16.0).peak for h in (made, made.reversed()))
    assert forward > backward + 0.04
    # Given the other way round, as keypoints may give it, the copy's own direction is found.
    best, found, _ = best_alignment(gray, grain, made.reversed(), DEFAULT_PARAMS)
    assert best.scale == pytest.approx(factor, abs=0.02) and found.peak >= forward - 0.01


def test_the_two_regions_are_drawn_only_where_windows_share_their_grain():
    from forensics_plugins.copy_move.figures import REGION_SIDE, regions_png

    rng = np.random.default_rng(12)
    cloned, _ = clone(scene(rng, (480, 640)), rng, "translation")
    result = analyse(_luma(encode(cloned, 90)), DEFAULT_PARAMS)
    png = regions_png(_luma(encode(cloned, 90)), result.details)
    assert png is not None and max(Image.open(io.BytesIO(png)).size) <= 3 * REGION_SIDE + 24
    assert regions_png(np.zeros((64, 64)), {"hypotheses": [], "best": None}) is None


def test_a_copy_differs_from_its_source_by_compression_noise_alone_in_the_difference_view():
    from forensics_plugins.copy_move.figures import REGION_SIDE, regions_png

    rng = np.random.default_rng(12)
    cloned, mask = clone(scene(rng, (480, 640)), rng, "translation")
    luma = _luma(encode(cloned, 90))
    result = analyse(luma, DEFAULT_PARAMS)
    views = np.asarray(Image.open(io.BytesIO(regions_png(luma, result.details))).convert("L"), dtype=np.float64)
    side = (views.shape[1] - 24) // 3
    target, difference = views[:, :side], views[:, 2 * (side + 12):]
    inner = (slice(side // 4, 3 * side // 4),) * 2
    # Within the copy the difference is mid-grey but for the compression's grain; the regions themselves are not.
    assert abs(np.median(difference[inner]) - 128) < 4 and np.std(difference[inner]) < np.std(target[inner]) / 2


def _points(x0, y0, side, step=12):
    ys, xs = np.mgrid[y0:y0 + side:step, x0:x0 + side:step]
    return np.column_stack([xs.ravel(), ys.ravel()]).astype(np.float64)


def test_a_printed_pattern_shares_its_grain_as_a_copy_does_but_goes_on_so_its_net_peak_is_low():
    """Wallpaper: one printed tile repeated, each instance the same print, under the camera's own noise."""
    from forensics_plugins.copy_move.identity import best_alignment, residual
    from forensics_plugins.copy_move.lattice import lattice_peak, lattice_peaks
    from forensics_plugins.copy_move.transforms import Hypothesis

    rng = np.random.default_rng(4)
    period = (136, 104)
    tile = 128 + 40 * cv2.GaussianBlur(rng.normal(0, 1, period[::-1]).astype(np.float32), (0, 0), 1.2)
    paper = np.tile(tile, (600 // period[1] + 1, 800 // period[0] + 1))[:600, :800]
    photo = cv2.GaussianBlur(paper, (0, 0), 0.7) + rng.normal(0, 1.5, paper.shape)
    gray = np.asarray(Image.open(io.BytesIO(encode(photo, 92))), dtype=np.float32)
    grain = residual(gray)
    source = _points(300, 250, 90)
    one_period = Hypothesis(np.array([[1.0, 0, period[0]], [0, 1.0, 0]]), source, source + (period[0], 0))
    aligned, same, _ = best_alignment(gray, grain, one_period, DEFAULT_PARAMS)
    beyond = lattice_peaks(gray, grain, aligned, DEFAULT_PARAMS)
    assert same.peak > 0.3, "a print shares its fine grain"
    assert all(p is not None and p > 0.3 for p in beyond) and same.peak - lattice_peak(beyond) < 0.1, beyond


def test_a_copy_does_not_go_on_and_keeps_its_grain_peak_as_its_net_peak(results):
    clones = [r for c, r in results if c.spliced and r.details["best"] is not None]
    assert clones and all(r.details["lattice_peak"] < 0.05 for r in clones)
    assert all(r.score == pytest.approx(max(0.0, r.details["net_peak"]), abs=1e-4) for r in clones)


def test_a_transform_is_split_into_rotation_scales_along_x_and_y_and_shear():
    from forensics_plugins.copy_move.transforms import Hypothesis

    theta = np.radians(12.0)
    rotation = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    matrix = np.column_stack([rotation @ np.array([[1.2, 0.1 * 0.9], [0.0, 0.9]]), [30.0, -5.0]])
    h = Hypothesis(matrix, np.zeros((0, 2)), np.zeros((0, 2)))
    assert h.rotation_deg == pytest.approx(12.0) and h.stretch == pytest.approx((1.2, 0.9, 0.1))
    similar = Hypothesis(cv2.getRotationMatrix2D((10.0, 20.0), 30.0, 0.8), np.zeros((0, 2)), np.zeros((0, 2)))
    assert similar.stretch == pytest.approx((0.8, 0.8, 0.0), abs=1e-9)


def test_a_copy_stretched_unevenly_is_described_as_the_affine_map_it_is():
    """MICC-F220's copies are scaled by different factors along x and y; the finding states both, not one scale."""
    img = scene(np.random.default_rng(0), (600, 800))
    side, (sx, sy), (tx, ty), (ax, ay) = 200, (60, 300), (430, 60), (1.1, 0.95)
    m = np.array([[ax, 0.0, tx - ax * sx], [0.0, ay, ty - ay * sy]])
    moved = cv2.warpAffine(img.astype(np.float32), m, (800, 600), flags=cv2.INTER_LINEAR)
    img[ty:ty + int(ay * side), tx:tx + int(ax * side)] = moved[ty:ty + int(ay * side), tx:tx + int(ax * side)]
    r = analyse(_luma(encode(img, 95)), DEFAULT_PARAMS)
    best = next(h for h in r.details["hypotheses"] if h["id"] == r.details["best"])
    assert best["aligned_on"] == "intensities (ECC)" and best["grain_peak"] > 0.3
    # Compared either way round: the copy's own map, or its inverse.
    assert (best["scale_xy"] == pytest.approx([ax, ay], abs=0.01)
            or best["scale_xy"] == pytest.approx([1 / ax, 1 / ay], abs=0.01))
    assert "affine transform (scale 1.10 along x and 0.95 along y, rotation 0°" in r.summary or \
        "affine transform (scale 0.91 along x and 1.05 along y, rotation 0°" in r.summary


def test_a_finding_made_before_scales_along_x_and_y_were_recorded_reads_as_a_similarity():
    from forensics_plugins.copy_move.detector import sheared, stretched

    earlier = {"scale": 0.93, "rotation_deg": 6.7}
    assert not stretched(earlier) and sheared(earlier) == ""
