"""Sub-pixel edge points (Canny NMS + Devernay correction)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import ndtr

from forensics_plugins.lens_distortion.edges import (
    EdgePoints,
    _band_maxima,
    _smoothed_gradient,
    auto_thresholds,
    pixel_neighbour_pairs,
    subpixel_edges,
)

H, W = 120, 160
MARGIN = 12  # points this close to the image border are not scored


def blurred_step(angle_deg: float, offset: float, seed: int, noise: float = 0.005):
    """A straight 0.2 -> 0.8 step blurred by a Gaussian of sigma 1 px, plus noise.

    The edge passes through ``centre`` with unit normal ``n`` (pointing to the
    bright side); pixel values are the exact blurred step at pixel centres.
    """
    t = np.deg2rad(angle_deg)
    n = np.array([np.cos(t), np.sin(t)])
    centre = np.array([(W - 1) / 2 + offset, (H - 1) / 2 - 0.6 * offset])
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float64)
    signed = (xx - centre[0]) * n[0] + (yy - centre[1]) * n[1]
    img = 0.2 + 0.6 * ndtr(signed / 1.0)
    img += np.random.default_rng(seed).normal(0.0, noise, img.shape)
    return img, centre, n


def interior(xy: np.ndarray) -> np.ndarray:
    return (
        (xy[:, 0] >= MARGIN) & (xy[:, 0] <= W - 1 - MARGIN) & (xy[:, 1] >= MARGIN) & (xy[:, 1] <= H - 1 - MARGIN)
    )


@pytest.mark.parametrize("angle_deg", [0.0, 8.0, 27.0, 45.0, 61.0, 90.0, 118.0, 153.0])
@pytest.mark.parametrize("offset", [0.0, 0.23, 0.41])
def test_step_edge_located_within_five_hundredths_of_a_pixel(angle_deg, offset):
    img, centre, n = blurred_step(angle_deg, offset, seed=int(angle_deg * 100 + offset * 1000))
    edges = subpixel_edges(img, sigma=1.0)
    inside = interior(edges.xy)
    dist = (edges.xy[inside] - centre) @ n
    # Only the one edge is found, along its whole interior length.
    assert np.all(np.abs(dist) < 0.5)
    # One point per row crossed (steep edges) or per column (flat ones).
    tangent = np.array([-n[1], n[0]])
    s = np.linspace(-W, W, 40001)
    length = interior(centre + s[:, None] * tangent).sum() * (s[1] - s[0])
    assert inside.sum() >= 0.95 * length * np.abs(tangent).max() - 2
    assert np.sqrt(np.mean(dist**2)) < 0.05


def test_normals_are_unit_and_point_to_the_bright_side():
    img, _, n = blurred_step(33.0, 0.3, seed=7)
    edges = subpixel_edges(img)
    assert np.allclose(np.hypot(edges.normal[:, 0], edges.normal[:, 1]), 1.0)
    inside = interior(edges.xy)
    assert np.all(edges.normal[inside] @ n > 0.99)
    # Central difference across the peak of a 0.6 step blurred by sqrt(1 + 1) px.
    sigma = np.sqrt(2.0)
    expected = 0.6 * (ndtr(1 / sigma) - ndtr(-1 / sigma)) / 2
    assert np.median(edges.strength[inside]) == pytest.approx(expected, rel=0.05)


def test_pixels_are_unique_and_hold_their_points():
    img, _, _ = blurred_step(71.0, 0.1, seed=3)
    edges = subpixel_edges(img)
    flat = edges.pixel[:, 0] * W + edges.pixel[:, 1]
    assert np.unique(flat).size == flat.size
    assert np.all(np.abs(edges.xy[:, 0] - edges.pixel[:, 1]) <= 0.5)
    assert np.all(np.abs(edges.xy[:, 1] - edges.pixel[:, 0]) <= 0.5)


def test_deterministic():
    img, _, _ = blurred_step(12.0, 0.2, seed=11)
    a, b = subpixel_edges(img), subpixel_edges(img.copy())
    for field in ("xy", "normal", "strength", "pixel"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


def test_flat_noisy_image_has_almost_no_edges():
    img = 0.5 + np.random.default_rng(5).normal(0.0, 0.02, (H, W))
    edges = subpixel_edges(img)
    assert len(edges) < 10
    low, high = auto_thresholds(img)
    assert (low, high) == (edges.low, edges.high)
    assert high >= 2.5 * low - 1e-12


def test_explicit_thresholds_are_honoured():
    img, _, _ = blurred_step(40.0, 0.0, seed=2)
    img[30:50, 30:50] += 0.05  # a weak square
    weak = subpixel_edges(img, low=0.005, high=0.01)
    strong = subpixel_edges(img, low=0.05, high=0.1)
    assert len(weak) > len(strong)
    assert np.all(strong.strength >= 0.05)
    assert (strong.low, strong.high) == (0.05, 0.1)
    with pytest.raises(ValueError):
        subpixel_edges(img, low=0.2, high=0.1)


def test_band_by_band_equals_whole_image():
    """The row bands must reproduce a whole-image computation exactly."""
    rng = np.random.default_rng(9)
    h, w = 203, 97  # several bands, the last one short
    yy, xx = np.mgrid[0:h, 0:w]
    img = np.zeros((h, w))
    for cx, cy, r, v in zip(rng.uniform(0, w, 12), rng.uniform(0, h, 12), rng.uniform(5, 30, 12), rng.uniform(-1, 1, 12)):
        img += v * ((xx - cx) ** 2 + (yy - cy) ** 2 < r * r)
    img = (img - img.min()) / np.ptp(img)
    low = 0.02
    got = subpixel_edges(img, sigma=1.3, low=low, high=low)
    gx, gy, norm = _smoothed_gradient(img, 1.3)
    flat, offset, horizontal = _band_maxima(gx, gy, norm, slice(1, h - 1), low)
    np.testing.assert_array_equal(got.pixel[:, 0] * w + got.pixel[:, 1], flat)
    row, col = np.divmod(flat, w)
    np.testing.assert_allclose(got.xy[:, 0], col + np.where(horizontal, offset, 0.0), atol=1e-9)
    np.testing.assert_allclose(got.xy[:, 1], row + np.where(horizontal, 0.0, offset), atol=1e-9)


def test_neighbour_pairs_match_brute_force():
    rng = np.random.default_rng(4)
    h, w = 9, 7
    flat = np.sort(rng.choice(h * w, 30, replace=False))
    i, j = pixel_neighbour_pairs(flat, w)
    got = {(int(flat[a]), int(flat[b])) for a, b in zip(i, j)}
    r, c = np.divmod(flat, w)
    want = {
        (int(flat[a]), int(flat[b]))
        for a in range(flat.size)
        for b in range(flat.size)
        if flat[a] < flat[b] and abs(r[a] - r[b]) <= 1 and abs(c[a] - c[b]) <= 1
    }
    assert got == want
    assert len(got) == i.size


def test_empty_and_invalid_input():
    edges = subpixel_edges(np.full((20, 30), 0.5))
    assert isinstance(edges, EdgePoints) and len(edges) == 0
    assert edges.xy.shape == (0, 2)
    with pytest.raises(ValueError):
        subpixel_edges(np.zeros((4, 4, 3)))
