"""Lone, scattered and curved departing lines are outliers, never a splice (fixed seeds).

Point-level scenes on a 1600x1200 frame seen through one camera (k1 0.08,
k2 0, centre at the image centre), straight lines with 0.15 px edge noise
smoothed along the line, as in ``test_consistency``. Beside them: lines that
depart on their own (from another camera), departing lines far apart or in
disagreement, and curved objects: a monitor bezel (four bulging edges), wheels
(circle arcs) and arches (half circles with their mouldings). Under the
strictest null (``SYNTHETIC_NULL``: Gaussian tails, no model error) the
structural rules alone must keep lone, scattered and parallel-bundle
departures from rejecting; under the default (real-photo) error model no
curved object may be called a splice.
"""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from forensics_plugins.lens_distortion import geometry
from forensics_plugins.lens_distortion.consistency import assess

SHAPE = (1200, 1600)
SCALE = geometry.norm_scale(SHAPE)
CAM = {"k1": 0.08, "k2": 0.0, "centre": (0.0, 0.0)}
OTHER = {"k1": -0.10, "k2": 0.0, "centre": (0.0, 0.0)}
SYNTHETIC_NULL = {"tau_k1": 0.0, "bow_rel": 0.0, "dof": np.inf}
ALPHA = 0.01


def _segment(mid, angle, length):
    t = np.arange(-length / 2, length / 2, 1.0 / SCALE)
    return np.asarray(mid) + np.outer(t, [np.cos(angle), np.sin(angle)])


def _arc(centre, radius, a0, a1):
    a = np.linspace(a0, a1, int(abs(a1 - a0) * radius * SCALE))
    return np.asarray(centre) + radius * np.column_stack((np.cos(a), np.sin(a)))


def _to_pixels(rng, undistorted, cams):
    out = []
    for p, cam in zip(undistorted, cams):
        d = geometry.distort(p, **cam)
        tangent = np.gradient(d, axis=0)
        normal = np.column_stack((-tangent[:, 1], tangent[:, 0])) / np.hypot(*tangent.T)[:, None]
        w = gaussian_filter1d(rng.standard_normal(len(d)), 2.0)
        out.append(geometry.to_pixels(d + normal * (0.15 * w / w.std() / SCALE)[:, None], SHAPE))
    return out


def _background(rng, n=14):
    """Straight lines spread over the frame, none radial, none near (0.5, 0.3)."""
    lines = []
    while len(lines) < n:
        mid = rng.uniform([-0.8, -0.55], [0.8, 0.55])
        angle = rng.uniform(0, np.pi)
        if abs(np.cos(angle - np.arctan2(mid[1], mid[0]))) > 0.8:
            continue
        p = _segment(mid, angle, rng.uniform(0.35, 0.7))
        if np.all(np.abs(p) < [0.97, 0.72]):
            lines.append(p)
    return lines


def _scene(seed, extra, extra_cams):
    rng = np.random.default_rng(seed)
    base = _background(rng)
    return _to_pixels(rng, base + extra, [CAM] * len(base) + extra_cams), len(base)


@pytest.mark.parametrize("seed", range(6))
def test_one_departing_line_is_an_outlier_not_a_splice(seed):
    lines, n = _scene(seed, [_segment((0.55, 0.35), 0.3, 0.5)], [OTHER])
    result = assess(lines, SHAPE, **SYNTHETIC_NULL)
    assert result.verdict == "consistent", result.test
    assert n in result.outlier_ids and n not in result.flagged_ids
    assert result.departures[n].flagged


@pytest.mark.parametrize("seed", range(4))
def test_scattered_departing_lines_are_not_a_splice(seed):
    """Three lines from another lens, far apart (more than the region radius): no compact region."""
    extra = [_segment((-0.7, -0.45), 0.4, 0.4), _segment((0.7, -0.45), 2.6, 0.4), _segment((0.0, 0.55), 0.1, 0.5)]
    lines, n = _scene(seed, extra, [OTHER] * 3)
    result = assess(lines, SHAPE, **SYNTHETIC_NULL)
    assert result.verdict == "consistent", result.test
    assert {n, n + 1, n + 2} <= set(result.outlier_ids)


@pytest.mark.parametrize("seed", range(4))
def test_neighbouring_lines_departing_in_opposite_directions_are_not_a_splice(seed):
    barrel = {"k1": 0.25, "k2": 0.0, "centre": (0.0, 0.0)}
    extra = [_segment((0.5, 0.3), 0.3, 0.45), _segment((0.6, 0.45), 2.0, 0.4)]
    lines, n = _scene(seed, extra, [OTHER, barrel])
    result = assess(lines, SHAPE, **SYNTHETIC_NULL)
    assert result.verdict == "consistent", result.test


@pytest.mark.parametrize("seed", range(4))
def test_parallel_contours_of_one_curved_object_are_not_a_splice(seed):
    """A bent pipe or moulding: three concentric arcs, bending together, all in one direction."""
    extra = [_arc((0.5, 1.6), r, -np.pi / 2 - 0.2, -np.pi / 2 + 0.2) for r in (1.25, 1.28, 1.31)]
    lines, n = _scene(seed, extra, [CAM] * 3)
    result = assess(lines, SHAPE, **SYNTHETIC_NULL)
    assert result.verdict == "consistent", result.test


def _bezel(centre, half, bulge):
    """Four edges of a rectangle bulging outwards by ``bulge`` (normalised) at their middles."""
    cx, cy = centre
    hx, hy = half
    t = np.linspace(-1, 1, int(2 * max(hx, hy) * SCALE))
    bow = bulge * (1 - t**2)
    return [
        np.column_stack((cx + hx * t, cy - hy - bow)),
        np.column_stack((cx + hx * t, cy + hy + bow)),
        np.column_stack((cx - hx - bow, cy + hy * t)),
        np.column_stack((cx + hx + bow, cy + hy * t)),
    ]


CURVED = {
    "monitor bezel": lambda: _bezel((0.45, 0.2), (0.25, 0.18), 0.012),
    "bezel at the centre": lambda: _bezel((0.0, 0.0), (0.35, 0.25), 0.01),
    "wheels": lambda: [_arc((-0.5, 0.35), 0.15, a, a + 1.2) for a in (0.2, 2.3, 4.4)]
    + [_arc((0.5, 0.35), 0.15, a, a + 1.2) for a in (0.2, 2.3, 4.4)],
    "arch with mouldings": lambda: [_arc((0.4, 0.1), r, np.pi + 0.15, 2 * np.pi - 0.15) for r in (0.3, 0.33)]
    + [_segment((0.1, 0.35), np.pi / 2, 0.45), _segment((0.7, 0.35), np.pi / 2, 0.45)],
}


@pytest.mark.parametrize("name", sorted(CURVED))
@pytest.mark.parametrize("seed", range(3))
def test_curved_objects_beside_straight_lines_are_never_convicted(name, seed):
    extra = CURVED[name]()
    lines, n = _scene(10 + seed, extra, [CAM] * len(extra))
    result = assess(lines, SHAPE)
    print(f"{name}, seed {seed}: {result.verdict}, p = {result.p_value:.3g}, outliers {result.outlier_ids}")
    assert result.verdict != "inconsistent", result.test
