"""copy_move's dense step on photos made here: a clone tool moved over a smooth area, and what must not look like one."""

import io

import cv2
import numpy as np
from PIL import Image

from forensics_core import Status
from forensics_core import grey_jpeg as encode
from forensics_plugins.copy_move.detector import analyse, regions_mask
from forensics_plugins.copy_move.spec import DEFAULT_PARAMS, GRAIN

SIZE = (480, 640)


def _luma(data):
    return np.asarray(Image.open(io.BytesIO(data)).convert("L"), dtype=np.float64) / 255.0


def _sky(seed, noise=3.0):
    """A smooth gradient with faint large-scale variation and sensor noise, float 0-255: no keypoints to speak of."""
    rng = np.random.default_rng(seed)
    h, w = SIZE
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    field = cv2.resize(rng.normal(0.0, 1.0, (4, 5)).astype(np.float32), (w, h), interpolation=cv2.INTER_CUBIC)
    return 90.0 + 0.12 * yy + 0.03 * xx + 6.0 * field + rng.normal(0.0, noise, SIZE)


def _stamped(img, source, move, side=128):
    """``img`` with the square of ``side`` at ``source`` (x, y) copied ``move`` (dx, dy) pixels away, and its mask."""
    (x, y), (dx, dy) = source, move
    out = img.copy()
    out[y + dy: y + dy + side, x + dx: x + dx + side] = img[y: y + side, x: x + side]
    mask = np.zeros(SIZE, bool)
    mask[y + dy: y + dy + side, x + dx: x + dx + side] = True
    return out, mask


def _dense(result):
    return [h for h in result.details["hypotheses"] if h["found_by"] == GRAIN]


def test_a_clone_stamp_over_a_smooth_area_is_found_by_its_grain():
    img, mask = _stamped(_sky(1), (100, 120), (213, 37))
    r = analyse(_luma(encode(img, 95)), DEFAULT_PARAMS)
    assert r.status is Status.OK and r.score is not None and r.score > 0.3, r.summary
    best = next(h for h in r.details["hypotheses"] if h["id"] == r.details["best"])
    assert best["found_by"] == GRAIN and "autocorrelation" in r.summary
    assert np.allclose(np.abs(best["translation_px"]), (213, 37), atol=1)
    assert best["n_inliers"] is None and best["grain_sigma"] > DEFAULT_PARAMS["dense_min_sigma"]
    assert (regions_mask(r.details, SIZE) & mask).sum() / mask.sum() >= 0.5


def test_a_stronger_compression_after_the_clone_weakens_its_grain_peak():
    """Saved at quality 90 the copy and its source lose different parts of their grain (other block phases)."""
    img, _ = _stamped(_sky(2), (100, 120), (213, 37))
    (found,) = _dense(analyse(_luma(encode(img, 90)), DEFAULT_PARAMS))
    assert np.allclose(np.abs(found["translation_px"]), (213, 37), atol=1) and 0.1 < found["grain_peak"] < 0.3


def test_a_smooth_photo_without_a_copy_has_no_repeating_grain():
    for seed in (2, 3, 4):
        r = analyse(_luma(encode(_sky(seed), 90)), DEFAULT_PARAMS)
        assert all(h["grain_peak"] is None or h["grain_peak"] < 0.1 for h in _dense(r)), r.details["hypotheses"]


def test_a_printed_pattern_is_not_searched_as_smooth_grain():
    """A ruler's identical ticks repeat their fine detail as a copy would; they are structure, left to the keypoints."""
    img = _sky(5)
    for x in range(40, 600, 23):
        cv2.line(img, (x, 380), (x, 400 if (x // 23) % 5 else 420), 20.0, 2)
    r = analyse(_luma(encode(img, 90)), DEFAULT_PARAMS)
    assert all(h["grain_peak"] is None or h["grain_peak"] < 0.2 for h in _dense(r)), r.details["hypotheses"]


def test_grain_the_compression_removed_gives_no_candidate():
    img, _ = _stamped(_sky(6, noise=0.3), (100, 120), (213, 37))
    assert _dense(analyse(_luma(encode(img, 75)), DEFAULT_PARAMS)) == []
