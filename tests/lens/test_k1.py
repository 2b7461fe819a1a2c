"""Per-line k1 estimators: the paper's (biased) one and the joint one."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from forensics_plugins.lens_distortion import geometry
from forensics_plugins.lens_distortion.k1 import (
    fit_lines,
    integrated_autocorrelation,
    k1_joint,
    k1_paper,
    signed_distance,
    trim_to_shortest,
)

SCALE = 800.0  # pixels per normalised unit (a 1600-px-wide frame)
Y = np.linspace(-0.5, 0.5, 801)  # one point per pixel along a 0.5-normalised half-length


def vertical_line(d: float, k1: float) -> np.ndarray:
    """Ideal distorted points of the vertical 3-D line x = d, shape (801, 2), normalised."""
    return geometry.distort(np.column_stack((np.full_like(Y, d), Y)), k1)


# Facts note, sec. 1: the paper's estimator shrinks towards zero with the distance.
PAPER_BIAS = [
    (0.05, 0.05, 0.0213),
    (0.10, 0.05, 0.0192),
    (0.20, 0.05, 0.0131),
    (0.40, 0.05, 0.0040),
    (0.60, 0.05, 0.0012),
    (0.40, -0.05, -0.0047),
]


@pytest.mark.parametrize(("d", "k1", "expected"), PAPER_BIAS)
def test_paper_estimator_reproduces_its_measured_bias(d, k1, expected):
    assert k1_paper(vertical_line(d, k1)) == pytest.approx(expected, rel=0.03, abs=5e-5)


@pytest.mark.parametrize(("d", "k1"), [(d, 0.05) for d in (0.05, 0.1, 0.2, 0.4, 0.6)] + [(0.4, -0.05), (0.6, -0.05)])
def test_joint_estimator_is_exact_on_ideal_points(d, k1):
    fit = k1_joint(vertical_line(d, k1), SCALE)
    assert fit.k1 == pytest.approx(k1, abs=1e-4)
    assert fit.residual_rms_px < 1e-6
    assert fit.distance == pytest.approx(d * (1 - k1 * d**2), abs=0.01)


def test_joint_estimator_with_offset_centre_and_k2():
    centre, k2 = (0.03, -0.02), 0.04
    points = geometry.distort(np.column_stack((np.full_like(Y, 0.45), Y)), 0.1, k2, centre)
    assert k1_joint(points, SCALE, k2=k2, centre=centre).k1 == pytest.approx(0.1, abs=1e-6)


def _scatter_and_stderr(noise, seeds=300):
    base = vertical_line(0.4, 0.05)
    rng = np.random.default_rng(7)
    fits = fit_lines([base + np.column_stack((noise(rng), np.zeros(len(Y)))) / SCALE for _ in range(seeds)], SCALE)
    k1 = np.array([f.k1 for f in fits])
    return k1, np.array([f.k1_stderr for f in fits]), np.array([f.residual_rms_px for f in fits])


def test_stderr_matches_scatter_for_white_noise():
    k1, stderr, rms = _scatter_and_stderr(lambda rng: rng.normal(0.0, 0.1, len(Y)))
    assert abs(k1.mean() - 0.05) < 3 * k1.std() / np.sqrt(k1.size)
    assert np.mean(stderr) == pytest.approx(k1.std(), rel=0.3)
    assert np.median(rms) == pytest.approx(0.1, rel=0.05)


def test_stderr_matches_scatter_for_correlated_noise():
    """Noise smoothed along the line (as JPEG and blur do): the white-noise error would be ~3x too small."""

    def smooth(rng):
        w = gaussian_filter1d(rng.standard_normal(len(Y)), 3.0)
        return 0.15 * w / w.std()

    k1, stderr, _ = _scatter_and_stderr(smooth)
    assert np.mean(stderr) == pytest.approx(k1.std(), rel=0.3)


def test_integrated_autocorrelation():
    rng = np.random.default_rng(3)
    assert integrated_autocorrelation(rng.standard_normal(5000)) == pytest.approx(1.0, abs=0.15)
    # Gaussian smoothing with sd s points: tau = 2 sqrt(pi) s.
    smooth = gaussian_filter1d(rng.standard_normal(20000), 4.0)
    assert integrated_autocorrelation(smooth) == pytest.approx(2 * np.sqrt(np.pi) * 4.0, rel=0.15)


def test_radial_line_carries_no_information():
    t = np.linspace(-0.6, 0.6, 900)
    radial = geometry.distort(np.column_stack((0.8 * t, 0.6 * t)), 0.1)
    fit = k1_joint(radial, SCALE)
    assert not fit.informative and fit.k1_stderr == np.inf
    # Information grows with the distance from the centre: 2 px away versus 240 px.
    rng = np.random.default_rng(0)
    errors = []
    for offset in (0.0025, 0.3):
        near = geometry.distort(np.column_stack((0.8 * t - 0.6 * offset, 0.6 * t + 0.8 * offset)), 0.1)
        errors.append(k1_joint(near + rng.normal(0.0, 0.1 / SCALE, near.shape), SCALE).k1_stderr)
    assert errors[0] > 50 * errors[1]


def test_signed_distance_follows_table_2_convention():
    t = np.linspace(-0.3, 0.3, 50)
    left = np.column_stack((np.full_like(t, -0.4), t))
    above = np.column_stack((t, np.full_like(t, -0.2)))
    assert signed_distance(left) == pytest.approx(-0.4)
    assert signed_distance(left * [-1, 1]) == pytest.approx(0.4)
    assert signed_distance(above) == pytest.approx(-0.2)
    assert signed_distance(above * [1, -1]) == pytest.approx(0.2)
    tilted = np.column_stack((t, -1.0 + 2.0 * t))  # steep line crossing y = 0 at x = 0.5
    assert signed_distance(tilted) == pytest.approx(1.0 / np.sqrt(5.0))


def test_trim_to_shortest_keeps_centred_parts():
    t = np.arange(0, 301, dtype=float)
    lines = [np.column_stack((t, 0 * t)), np.column_stack((0 * t[:101], t[:101] + 7.0))]
    long_, short = trim_to_shortest(lines)
    assert len(short) == 101 and np.ptp(long_[:, 0]) == pytest.approx(100.0)
    assert long_[:, 0].mean() == pytest.approx(150.0)


def test_deterministic():
    rng = np.random.default_rng(11)
    points = vertical_line(0.3, 0.08) + rng.normal(0.0, 0.2 / SCALE, (len(Y), 2))
    assert k1_joint(points, SCALE) == k1_joint(points.copy(), SCALE)


def test_paper_k1_is_undefined_for_too_few_or_coincident_points():
    assert np.isnan(k1_paper(np.zeros((5, 2))))
    assert np.isnan(k1_paper(np.array([[0.1, 0.2], [0.3, 0.2]])))


def test_a_drawn_noiseless_line_gets_the_edge_noise_floor_not_infinite_weight():
    # A drawn checkerboard's edges fit their lines exactly; a zero residual made a zero standard error, an
    # infinite weight and a crash of the global fit ("Residuals are not finite") on a 25 MP board.
    from forensics_plugins.lens_distortion.k1 import MIN_EDGE_NOISE_PX, fit_lines

    t = np.linspace(-0.4, 0.4, 400)
    points = np.column_stack((np.full_like(t, 0.3), t))
    (fit,) = fit_lines([points], 2000.0)
    assert fit.residual_rms_px < MIN_EDGE_NOISE_PX
    assert np.isfinite(fit.k1_stderr) and fit.k1_stderr > 0
