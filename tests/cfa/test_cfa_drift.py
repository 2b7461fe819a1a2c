"""A mosaic that drifts smoothly across the photo (a slight resampling of the whole frame) is processing, not a paste."""

import numpy as np
import pytest

from forensics_core import HEADLINE_WORDS, PROCESSING_KEY, Status
from forensics_plugins.cfa import synth
from forensics_plugins.cfa.detector import analyse
from forensics_plugins.cfa.drift import AffineDrift, DriftCheck, DriftFit, fit_drift
from forensics_plugins.cfa.residuals import block_features
from forensics_plugins.cfa.spec import DEFAULT_PARAMS
from forensics_plugins.cfa.votes import phase_votes

SIZE = (1152, 1536)
#: Green moves to the other diagonal in two opposite corners, where the displacement passes half a pixel.
DRIFT = AffineDrift(dx=(0.0, 0.6, 0.3), dy=(0.0, 0.0, 0.0))
CENTRE = (slice(500, 660), slice(700, 860))
CORNER = (slice(0, 240), slice(1296, 1536))


def _nearest(rgb: np.ndarray, drift: AffineDrift) -> np.ndarray:
    """The photo resampled by ``drift`` with nearest-neighbour interpolation."""
    h, w = rgb.shape[:2]
    y, x = np.mgrid[0:h, 0:w]
    dy, dx = drift.displacement(y, x, (h, w))
    return rgb[np.clip(np.rint(y - dy).astype(int), 0, h - 1), np.clip(np.rint(x - dx).astype(int), 0, w - 1)]


def _moved_by_one_column(rgb: np.ndarray, piece: tuple[slice, slice]) -> np.ndarray:
    """``rgb`` with ``piece`` replaced by the pixels one column to its left: the same content on the other diagonal."""
    out = rgb.copy()
    rows, cols = piece
    out[rows, cols] = rgb[rows, cols.start - 1:cols.stop - 1]
    return out


@pytest.fixture(scope="module")
def photos():
    host = synth.make_pair(7, SIZE, algorithm="bilinear", shift=(0, 1), fraction=0.2)[0]
    drifted = _nearest(host.rgb, DRIFT)
    return {"drifted": drifted, "pasted": _moved_by_one_column(drifted, CENTRE),
            "cornered": _moved_by_one_column(host.rgb, CORNER)}


def _overlap(box, piece) -> float:
    x0, y0, x1, y1 = box
    truth = np.zeros(SIZE, bool)
    truth[piece] = True
    found = np.zeros(SIZE, bool)
    found[y0:y1, x0:x1] = True
    return (found & truth).sum() / truth.sum()


def test_the_bands_of_a_drifted_mosaic_are_explained_as_processing(photos):
    result = analyse(photos["drifted"], DEFAULT_PARAMS)
    d = result.details
    assert result.status is Status.OK and d["regions"] == [] and result.nfa > 0.01
    # The plain scan found both corners; the drift the rest of the photo shows predicts each.
    assert len(d["regions_explained"]) == 2 and all(r["drift"]["explained"] for r in d["regions_explained"])
    assert d[PROCESSING_KEY]["kind"] == "slight resampling"
    assert "processing" in result.headline and "drift" in result.summary
    assert len(result.headline.split()) <= HEADLINE_WORDS


def test_a_piece_pasted_into_the_drifted_photo_is_still_found(photos):
    result = analyse(photos["pasted"], DEFAULT_PARAMS)
    regions = result.details["regions"]
    assert result.status is Status.OK and result.nfa < 1e-6
    assert _overlap(regions[0]["bbox_px"], CENTRE) > 0.5
    assert len(result.details["regions_explained"]) == 2


def test_a_piece_pasted_at_a_corner_of_an_undrifted_photo_is_not_explained(photos):
    result = analyse(photos["cornered"], DEFAULT_PARAMS)
    assert result.status is Status.OK and result.nfa < 1e-6
    assert _overlap(result.details["regions"][0]["bbox_px"], CORNER) > 0.5
    assert "regions_explained" not in result.details and PROCESSING_KEY not in result.details
    assert not any(c["explained"] for c in result.details["drift_checks"]["regions"])


def test_the_drift_is_recovered_from_the_votes(photos):
    p = DEFAULT_PARAMS
    feats = block_features(photos["drifted"], 16, 255.0, p["log_offset"])
    usable = (feats.clipped <= p["max_clipped_fraction"]) & (feats.activity >= p["min_activity"])
    votes = phase_votes(feats.features, feats.colour, usable, p["shrinkage"], p["colour_ridge"])
    fit = fit_drift(votes.shift_vote, usable, 16, SIZE)
    # cos is even: the field is known up to its sign.
    terms = np.array(fit.drift.dx) * np.sign(fit.drift.dx[1])
    assert np.allclose(terms[1:], DRIFT.dx[1:], atol=0.15) and abs(terms[0]) < 0.15
    assert max(np.abs(fit.drift.dy[1:])) < 0.05 and fit.gain > 100


@pytest.mark.parametrize("change, explained", [
    ({}, True),
    ({"borders": 1}, False),
    ({"outside_gain": 10.0}, False),
    ({"region_gain": 20.0}, False),
    ({"share": 0.4}, False),
    ({"flip_log10_p": -1.0}, False),
])
def test_a_region_is_explained_only_by_a_drift_the_rest_shows_and_in_a_bands_shape(change, explained):
    fit = DriftFit(AffineDrift((0.0, 0.6, 0.3), (0.0, 0.0, 0.0)), 300.0, (0.5, 0.5), (3.0, 3.0), 5000)
    base = {"outside_gain": 300.0, "region_gain": 80.0, "own_gain": 100.0, "share": 0.07, "span_px": 1.3,
            "flip_log10_p": -5.0, "borders": 2}
    assert DriftCheck(fit, **{**base, **change}).explained is explained
