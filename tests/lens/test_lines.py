"""Distorted straight lines gathered from sub-pixel edge points."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy.spatial import cKDTree

from forensics_plugins.lens_distortion.edges import subpixel_edges
from forensics_plugins.lens_distortion.geometry import distort, to_normalised, to_pixels, undistort
from forensics_plugins.lens_distortion.lines import DistortedLine, extract_lines

CALIBRATION = Path(__file__).resolve().parents[1] / "data" / "calibration"


# --------------------------------------------------------------------------- synthetic scene

SHAPE = (480, 640)
#: Corners of a quadrilateral, undistorted normalised coordinates, in order.
QUAD = np.array([[-0.72, -0.50], [0.70, -0.56], [0.74, 0.50], [-0.68, 0.54]])
CIRCLE_CENTRE = np.array([320.0, 250.0])  # pixels, drawn directly in the image
CIRCLE_RADIUS = SHAPE[0] / 4


def render(k1: float, seed: int, supersample: int = 4) -> np.ndarray:
    """Anti-aliased scene seen through radial distortion ``k1``.

    A grey quadrilateral (straight edges in the undistorted scene) over a
    background that is bright left of the vertical axis and dark right of it,
    so the top and bottom edges flip polarity halfway; inside it a dark disc,
    a circle in the image itself. Each pixel averages ``supersample**2``
    samples mapped to the undistorted scene (geometry.undistort).
    """
    h, w = SHAPE
    rows, cols = np.mgrid[0:h, 0:w].astype(np.float64)
    acc = np.zeros(SHAPE)
    sub = (np.arange(supersample) + 0.5) / supersample - 0.5
    edges = np.roll(QUAD, -1, axis=0) - QUAD
    for dy in sub:
        for dx in sub:
            xy = np.column_stack(((cols + dx).ravel(), (rows + dy).ravel()))
            u = undistort(to_normalised(xy, SHAPE), k1)
            rel = u[:, None, :] - QUAD[None]
            inside = np.all(edges[None, :, 0] * rel[..., 1] - edges[None, :, 1] * rel[..., 0] > 0, axis=1)
            value = np.where(u[:, 0] < 0, 0.9, 0.15)
            value = np.where(inside, 0.55, value)
            disc = np.hypot(*(xy - CIRCLE_CENTRE).T) < CIRCLE_RADIUS
            acc += np.where(disc, 0.15, value).reshape(SHAPE)
    img = acc / supersample**2
    return img + np.random.default_rng(seed).normal(0.0, 0.003, SHAPE)


def true_edge(i: int, k1: float) -> np.ndarray:
    """Densely sampled distorted image of quadrilateral side ``i``, pixels, shape (M, 2)."""
    s = np.linspace(0.0, 1.0, 40001)[:, None]
    a, b = QUAD[i], QUAD[(i + 1) % 4]
    return to_pixels(distort(a + s * (b - a), k1), SHAPE)


def distance_to(curve: np.ndarray, points: np.ndarray) -> np.ndarray:
    return cKDTree(curve).query(points)[0]


@pytest.fixture(scope="module", params=[0.1, -0.08], ids=["barrel", "pincushion"])
def synthetic(request):
    k1 = request.param
    img = render(k1, seed=1)
    edges = subpixel_edges(img, sigma=1.0)
    return k1, edges, extract_lines(edges, SHAPE, SHAPE[0] / 4)


def test_each_straight_edge_is_one_line_on_its_distorted_curve(synthetic):
    k1, _, lines = synthetic
    for side in range(4):
        curve = true_edge(side, k1)
        near = [ln for ln in lines if np.median(distance_to(curve, ln.points)) < 1.0]
        assert len(near) == 1, f"side {side}: {len(near)} lines"
        d = distance_to(curve, near[0].points)
        assert np.sqrt(np.mean(d**2)) < 0.1
        # The whole side is covered, but for the corners (turn cut) and the T-junction.
        arc = np.hypot(*np.diff(curve, axis=0).T).sum()
        assert near[0].length_px > arc - 40


def test_polarity_flips_are_gathered(synthetic):
    k1, edges, lines = synthetic
    for side in (0, 2):  # top and bottom sides cross the background boundary
        curve = true_edge(side, k1)
        line = next(ln for ln in lines if np.median(distance_to(curve, ln.points)) < 1.0)
        assert line.pieces >= 2
        chord = line.points[-1] - line.points[0]
        across = np.array([-chord[1], chord[0]])
        polarity = np.sign(edges.normal[line.edge_index] @ across)
        assert 0.3 < np.mean(polarity > 0) < 0.7
        np.testing.assert_array_equal(np.diff(line.piece) >= 0, True)
        assert set(line.piece) == set(range(line.pieces))


def test_circle_is_not_a_line(synthetic):
    _, _, lines = synthetic
    for ln in lines:
        off_circle = np.abs(np.hypot(*(ln.points - CIRCLE_CENTRE).T) - CIRCLE_RADIUS)
        assert np.median(off_circle) > 2.0


def test_only_the_straight_edges_are_returned(synthetic):
    k1, _, lines = synthetic
    curves = np.concatenate([true_edge(side, k1) for side in range(4)])
    assert len(lines) == 4
    for ln in lines:
        assert isinstance(ln, DistortedLine)
        assert ln.points.shape == (ln.edge_index.size, 2)
        assert ln.piece.shape == ln.edge_index.shape
        assert ln.length_px >= SHAPE[0] / 4
        assert np.all(distance_to(curves, ln.points) < 1.5)


def test_gathering_model_sees_the_distortion_sign(synthetic):
    k1, _, lines = synthetic
    # The two long sides far from the centre bend most; their screening k1 has the right sign.
    for side in (0, 2):
        curve = true_edge(side, k1)
        line = next(ln for ln in lines if np.median(distance_to(curve, ln.points)) < 1.0)
        assert np.sign(line.k1) == np.sign(k1)
        assert abs(line.k1 - k1) < 0.05


def test_deterministic(synthetic):
    _, edges, lines = synthetic
    again = extract_lines(edges, SHAPE, SHAPE[0] / 4)
    assert len(again) == len(lines)
    for a, b in zip(lines, again):
        np.testing.assert_array_equal(a.points, b.points)
        np.testing.assert_array_equal(a.edge_index, b.edge_index)


def test_strong_curvature_is_not_gathered_as_a_line():
    """An arc that no |k1| <= max_k1 can straighten is rejected, a looser bound accepts it."""
    h, w = SHAPE
    rows, cols = np.mgrid[0:h, 0:w].astype(np.float64)
    # A gentle arc across the image: sagitta 12 px over 500 px, near the centre
    # where radial distortion barely bends lines.
    radius = 500.0**2 / (8 * 12.0)
    centre = np.array([319.5, 240.0 + radius])
    img = np.where(np.hypot(cols - centre[0], rows - centre[1]) < radius, 0.7, 0.3)
    img = img + np.random.default_rng(2).normal(0.0, 0.003, SHAPE)
    edges = subpixel_edges(img)
    assert extract_lines(edges, SHAPE, 200.0) == []
    assert len(extract_lines(edges, SHAPE, 200.0, max_k1=5.0)) == 1


# --------------------------------------------------------------------------- chessboard photos


def load(view: int) -> np.ndarray:
    with Image.open(CALIBRATION / f"left{view:02d}.jpg") as im:
        return np.asarray(im.convert("L"), dtype=np.float64) / 255.0


def polarity_flips(line: DistortedLine, normals: np.ndarray) -> int:
    chord = line.points[-1] - line.points[0]
    sign = np.sign(normals[line.edge_index] @ np.array([-chord[1], chord[0]]))
    return int(np.count_nonzero(np.diff(sign)))


def orientation_deg(line: DistortedLine) -> float:
    chord = line.points[-1] - line.points[0]
    return float(np.degrees(np.arctan2(chord[1], chord[0])) % 180.0)


@pytest.mark.parametrize("view", [1, 2, 3, 4, 5])
def test_chessboard_grid_lines_are_gathered(view):
    gray = load(view)
    h, w = gray.shape
    edges = subpixel_edges(gray)
    lines = extract_lines(edges, gray.shape, h / 4)
    assert len(lines) >= 10
    assert all(ln.length_px >= h / 4 for ln in lines)
    # Most lines are gathered from several chains.
    assert np.mean([ln.pieces > 1 for ln in lines]) >= 0.5

    # Inner grid lines alternate black/white on each side: gathered across flips.
    grid = [ln for ln in lines if polarity_flips(ln, edges.normal) >= 3]
    assert len(grid) >= 12  # of the 6 + 9 inner grid lines
    # Two families of directions (the two grid directions); every line spans the
    # board, so it meets (nearly) every line of the other family. The crossings
    # themselves are cut out as junctions, hence the few pixels of slack.
    angles = np.array([orientation_deg(ln) for ln in grid])
    gap = np.abs((angles - angles[0] + 90.0) % 180.0 - 90.0)
    families = [[grid[i] for i in np.flatnonzero(gap < 30.0)], [grid[i] for i in np.flatnonzero(gap >= 30.0)]]
    assert all(len(f) >= 5 for f in families)
    for mine, other in (families, families[::-1]):
        trees = [cKDTree(ln.points) for ln in other]
        for ln in mine:
            assert ln.pieces >= 5
            met = [tree.query(ln.points)[0].min() < 8.0 for tree in trees]
            assert np.mean(met) >= 0.8


@pytest.mark.parametrize("view", [1, 2, 3, 4, 5])
def test_no_line_hugs_the_image_border(view):
    gray = load(view)
    h, w = gray.shape
    lines = extract_lines(subpixel_edges(gray), gray.shape, h / 4)
    for ln in lines:
        x, y = ln.points[:, 0], ln.points[:, 1]
        assert min(x.min(), y.min(), w - 1 - x.max(), h - 1 - y.max()) >= 6.0
    if view == 1:
        # left01.jpg has a dark frame a few pixels thick along its top border.
        assert not any(ln.points[:, 1].max() < 20 for ln in lines)


# --------------------------------------------------------------------------- chain ordering


def test_chains_are_ordered_and_cycles_opened():
    from forensics_plugins.lens_distortion.lines import _order_chains

    # 4 -> 0 -> 2 (open chain), 1 -> 5 -> 3 -> 1 (closed), 6 alone.
    succ = np.array([2, 5, -1, 1, 0, 3, -1])
    order, starts = _order_chains(succ)
    chains = np.split(order, np.flatnonzero(starts)[1:])
    as_lists = sorted(c.tolist() for c in chains)
    assert as_lists == [[1, 5, 3], [4, 0, 2], [6]]
