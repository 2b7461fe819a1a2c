"""Per-line estimates of the radial distortion coefficient ``k1``.

Two estimators are provided:

``paper``
    Exactly the procedure of Chennamma & Rangarajan, sec. 3.3, eqs. (6)-(10):
    a straight line is fitted by linear regression to the *distorted* points
    and held fixed while ``k1`` is found by Levenberg-Marquardt on the
    residuals of eq. (8). Undistortion also moves the line, so with the line
    frozen ``k1`` trades curvature against shift and the estimate shrinks
    towards zero as the line's distance from the centre grows (see
    ``tests/lens/test_k1.py`` for the measured bias).

``joint`` (default)
    ``k1`` and the undistorted line ``x cos(theta) + y sin(theta) = rho`` are
    fitted together, with perpendicular residuals in pixels. The line is
    parametrised by an explicit angle and offset, so its normal cannot flip
    sign between iterations (the failure mode of a residual built from a
    fresh SVD normal at every step). The estimate is unbiased on ideal data
    and comes with a standard error.

All point arrays are normalised coordinates (see :mod:`.geometry`): image
centre at the origin, divided by :func:`.geometry.norm_scale`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

__all__ = [
    "LineK1",
    "fit_lines",
    "integrated_autocorrelation",
    "k1_joint",
    "k1_paper",
    "paper_line",
    "signed_distance",
    "trim_to_shortest",
]

# Relative size below which the part of the k1 column that the line's own
# (theta, rho) cannot absorb counts as zero: the line is radial and says
# nothing about k1 (a radial line stays straight under radial distortion).
_RADIAL_TOLERANCE = 1e-10
#: Sub-pixel edges are never located better than this (8-bit grey levels): a drawn, noiseless edge fits its line
#: exactly, and a zero residual would give its line infinite weight.
MIN_EDGE_NOISE_PX = 0.01

_K1_STARTS = (0.0, -0.25, 0.25)  # starts of the single-line fit, normalised k1


@dataclass(frozen=True)
class LineK1:
    """Joint ``k1`` fit of one line.

    Attributes
    ----------
    k1 : float
        Radial coefficient (dimensionless, normalised radii; ``> 0`` barrel).
    k1_stderr : float
        Standard error of ``k1`` allowing for correlated edge noise: the
        white-noise error times ``sqrt(n_points / n_effective)``. ``inf`` for
        a line that carries no information on ``k1`` (through the centre).
    k1_stderr_white : float
        Standard error assuming independent points (Gauss-Newton covariance
        with the residual variance on ``n_points - 3`` degrees of freedom).
    residual_rms_px : float
        Root-mean-square perpendicular residual, pixels, on ``n_points - 3``
        degrees of freedom.
    n_points : int
        Number of points.
    n_effective : float
        Number of effectively independent points, ``n_points / tau`` with
        ``tau`` from :func:`integrated_autocorrelation` of the residuals.
    distance : float
        Signed normalised distance of the observed line from the image centre
        (:func:`signed_distance`).
    theta, rho : float
        Fitted undistorted line ``x cos(theta) + y sin(theta) = rho``,
        normalised, in the frame of the distortion centre's coordinates.
    leverage_px : float
        Root-mean-square displacement, pixels per unit ``k1``, that ``k1``
        causes and the line's own ``(theta, rho)`` cannot absorb. A
        systematic, line-shaped error of ``e`` pixels RMS is therefore
        indistinguishable from a ``k1`` change of ``e / leverage_px``.
    """

    k1: float
    k1_stderr: float
    k1_stderr_white: float
    residual_rms_px: float
    n_points: int
    n_effective: float
    distance: float
    theta: float
    rho: float
    leverage_px: float

    @property
    def informative(self) -> bool:
        """Whether the line constrains ``k1`` at all (finite standard error)."""
        return bool(np.isfinite(self.k1_stderr))


def paper_line(points_norm: np.ndarray) -> tuple[np.ndarray, float]:
    """Regression line of the distorted points, paper eqs. (8)-(10).

    Parameters
    ----------
    points_norm : ndarray, shape (N, 2)
        Distorted points, normalised.

    Returns
    -------
    normal : ndarray, shape (2,)
        ``(n_x, n_y)`` of the Hesse normal form (8).
    d0 : float
        Offset ``d_0`` of (8).

    Notes
    -----
    The paper prints, for case 2, ``d = (mean(X^2) mean(Y) - mean(X)
    mean(XY)) / var(Y)``, which is the case-1 numerator copied unchanged;
    regressing ``x`` on ``y`` gives ``d = (mean(Y^2) mean(X) - mean(Y)
    mean(XY)) / var(Y)``, which is used here (the printed form is not even
    invariant to a shift of ``y``).
    """
    x, y = np.asarray(points_norm, dtype=np.float64).T
    mx, my = x.mean(), y.mean()
    mxx, myy, mxy = (x * x).mean(), (y * y).mean(), (x * y).mean()
    var_x, var_y = mxx - mx * mx, myy - my * my
    if var_x >= var_y:  # case 1, eq. (9): y = a x + b
        a = (mxy - mx * my) / var_x
        b = (mxx * my - mx * mxy) / var_x
        norm = np.hypot(a, 1.0)
        return np.array([-a, 1.0]) / norm, b / norm
    c = (mxy - mx * my) / var_y  # case 2, eq. (10): x = c y + d
    d = (myy * mx - my * mxy) / var_y
    norm = np.hypot(c, 1.0)
    return np.array([1.0, -c]) / norm, d / norm


def k1_paper(points_norm: np.ndarray) -> float:
    """``k1`` of one line by the paper's procedure, eqs. (6)-(10).

    The line (8) is fitted to the distorted points (:func:`paper_line`) and
    kept fixed; ``k1`` minimises ``sum eps_i^2`` with
    ``eps_i = n . p_d,i (1 + k1 r_d,i^2) - d0`` (eqs. 6-8) by
    Levenberg-Marquardt, as the paper does with MATLAB's ``lsqnonlin``.
    Centre of distortion at the image centre, no ``k2`` (paper eqs. 4-5).

    Parameters
    ----------
    points_norm : ndarray, shape (N, 2)
        Distorted points, normalised.

    Returns
    -------
    float
        ``k1`` (biased towards zero; see the module docstring); NaN for
        fewer than three points or points that all coincide.

    References
    ----------
    .. [1] H. R. Chennamma, L. Rangarajan, Image splicing detection using
       inherent lens radial distortion, IJCSI 7(6), 2010, eqs. (6)-(10).

    Examples
    --------
    A straight line at half the normalised radius, bowed by ``k1 = 0.1``:
    the paper's estimate, with its line frozen, sees little of it (the bias
    :func:`fit_lines` removes):

    >>> from forensics_plugins.lens_distortion.geometry import distort
    >>> x = np.linspace(-0.6, 0.6, 200)
    >>> bowed = distort(np.column_stack((x, np.full_like(x, 0.5))), k1=0.1)
    >>> round(k1_paper(bowed), 4)
    0.0064
    """
    p = np.asarray(points_norm, dtype=np.float64)
    if len(p) < 3 or np.ptp(p, axis=0).max() == 0:
        # Trimmed to the shortest line (sec. 4.3), a line can keep too few
        # distinct points to bow: the paper's k1 is then undefined.
        return float("nan")
    normal, d0 = paper_line(p)
    along_normal = p @ normal
    r2 = np.einsum("ij,ij->i", p, p)

    def residuals(k: np.ndarray) -> np.ndarray:
        return along_normal * (1.0 + k[0] * r2) - d0

    def jacobian(k: np.ndarray) -> np.ndarray:
        return (along_normal * r2)[:, None]

    return float(least_squares(residuals, x0=[0.0], jac=jacobian, method="lm").x[0])


def trim_to_shortest(lines: Sequence[np.ndarray]) -> list[np.ndarray]:
    """Trim every line to the arc length of the shortest one (paper sec. 4.3).

    The central part of each polyline is kept, so a trimmed line keeps its
    midpoint. Units are those of the input (pixels or normalised). The paper
    also requires the shortest line to be at least a third of the image
    height; dropping shorter lines is left to the line extractor.

    Parameters
    ----------
    lines : sequence of ndarray, each shape (N_j, 2)
        Points ordered along each line.

    Returns
    -------
    list of ndarray, each shape (M_j, 2), M_j <= N_j
        Empty when ``lines`` is empty.
    """
    if not lines:
        return []
    arcs = [np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T)))) for p in lines]
    shortest = min(s[-1] for s in arcs)
    return [
        np.asarray(p)[np.abs(s - s[-1] / 2.0) <= shortest / 2.0 + 1e-12 * max(shortest, 1.0)]
        for p, s in zip(lines, arcs)
    ]


def _tls(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Total-least-squares line of points, shape (N, 2): unit normal and offset."""
    mean = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - mean, full_matrices=False)
    normal = vt[-1]
    return normal, float(normal @ mean)


def signed_distance(points_norm: np.ndarray) -> float:
    """Signed normalised distance of a line from the image centre (paper Table 2).

    The magnitude is the perpendicular distance from the origin (the image
    centre) to the total-least-squares line of the observed points. The sign
    follows the paper's tables, which list lines "from left to right" with
    negative distances on the left: for a line closer to vertical
    (``|n_x| >= |n_y|`` for its unit normal ``n``) the sign is that of the
    ``x`` coordinate of the foot of the perpendicular (negative left of the
    centre); for a line closer to horizontal, that of its ``y`` coordinate
    (negative above the centre, since ``y`` grows downwards).

    Parameters
    ----------
    points_norm : ndarray, shape (N, 2)
        Points of one line, normalised.

    Returns
    -------
    float
        Signed distance, normalised units.
    """
    normal, rho = _tls(np.asarray(points_norm, dtype=np.float64))
    foot = rho * normal
    axis = 0 if abs(normal[0]) >= abs(normal[1]) else 1
    return float(np.copysign(abs(rho), foot[axis])) if foot[axis] != 0 else abs(rho)


def integrated_autocorrelation(residuals: np.ndarray) -> float:
    """Integrated autocorrelation time ``tau`` of residuals ordered along a line.

    ``tau = 1 + 2 sum_k rho_k`` over lags ``k >= 1`` up to the first
    non-positive sample autocorrelation (an initial-positive-sequence
    truncation, capped at a quarter of the length), floored at 1. For an
    estimate that is a smooth weighted sum of the residuals (the ``k1`` of a
    line is one: its regressor ``r^2 n.p`` varies slowly along the line), the
    variance under correlated noise is ``tau`` times the white-noise variance,
    because ``tau sigma^2`` is the noise power at low frequency.

    Parameters
    ----------
    residuals : ndarray, shape (N,)

    Returns
    -------
    float
        ``tau >= 1``; ``N / tau`` is the effective number of independent points.
    """
    e = np.asarray(residuals, dtype=np.float64) - np.mean(residuals)
    n = e.size
    spectrum = np.fft.rfft(e, 2 * n)
    acov = np.fft.irfft(spectrum * np.conj(spectrum))[: max(n // 4, 1) + 1]
    if acov[0] <= 0:
        return 1.0
    rho = acov[1:] / acov[0]
    stop = np.flatnonzero(rho <= 0)
    positive = rho[: stop[0]] if stop.size else rho
    return float(max(1.0, 1.0 + 2.0 * positive.sum()))


@dataclass(frozen=True)
class _Stacked:
    """Lines concatenated for vectorised per-line sums."""

    points: np.ndarray  # (N, 2)
    starts: np.ndarray  # (m,) first index of each line
    counts: np.ndarray  # (m,)
    ids: np.ndarray  # (N,) line index of each point

    @classmethod
    def of(cls, lines: Sequence[np.ndarray]) -> _Stacked:
        counts = np.array([len(p) for p in lines], dtype=np.intp)
        starts = np.concatenate(([0], np.cumsum(counts)[:-1])).astype(np.intp)
        points = np.concatenate([np.asarray(p, dtype=np.float64).reshape(-1, 2) for p in lines])
        return cls(points, starts, counts, np.repeat(np.arange(counts.size), counts))

    def sum(self, values: np.ndarray) -> np.ndarray:
        """Per-line sums along axis 0: shape (N, ...) -> (m, ...)."""
        return np.add.reduceat(values, self.starts, axis=0)

    def subset(self, keep: np.ndarray) -> _Stacked:
        """The lines where ``keep`` (shape (m,), bool) is true, in order."""
        counts = self.counts[keep]
        starts = np.concatenate(([0], np.cumsum(counts)[:-1])).astype(np.intp)
        return _Stacked(self.points[keep[self.ids]], starts, counts, np.repeat(np.arange(counts.size), counts))


def _line_model(
    s: _Stacked, params: np.ndarray, k2: float, centre: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Residuals, shape (N,), and Jacobian, shape (N, 3), normalised units.

    ``params`` has shape (m, 3): ``(k1, theta, rho)`` per line; residual
    ``e = n(theta) . u - rho`` with ``u`` the undistorted point (paper
    eqs. 6-8 extended by ``k2`` and a centre of distortion).
    """
    k1, theta, rho = (params[s.ids, i] for i in range(3))
    q = s.points - centre
    r2 = np.einsum("ij,ij->i", q, q)
    u = centre + q * (1.0 + k1 * r2 + k2 * r2 * r2)[:, None]
    cos, sin = np.cos(theta), np.sin(theta)
    residual = u[:, 0] * cos + u[:, 1] * sin - rho
    jac = np.column_stack(
        (r2 * (q[:, 0] * cos + q[:, 1] * sin), u[:, 1] * cos - u[:, 0] * sin, -np.ones_like(r2))
    )
    return residual, jac


def _initial_lines(s: _Stacked, k1: np.ndarray) -> np.ndarray:
    """``(k1, theta, rho)`` start per line from the TLS line of the raw points."""
    params = np.empty((s.counts.size, 3))
    params[:, 0] = k1
    for j, (a, n) in enumerate(zip(s.starts, s.counts)):
        normal, rho = _tls(s.points[a : a + n])
        params[j, 1:] = np.arctan2(normal[1], normal[0]), rho
    return params


def _levenberg_marquardt(
    s: _Stacked, params: np.ndarray, k2: float, centre: np.ndarray, max_iter: int = 50
) -> np.ndarray:
    """Independent 3-parameter LM fits of all lines at once (stacked 3x3 solves).

    A line leaves the stack once an accepted step no longer lowers its cost
    (or its damping has grown past any use), so later iterations cost only
    the points of the lines still moving.
    """
    out = np.array(params, dtype=np.float64)
    active = np.arange(s.counts.size)
    lam = np.full(s.counts.size, 1e-3)
    residual, jac = _line_model(s, params, k2, centre)
    cost = s.sum(residual**2)
    for _ in range(max_iter):
        normal = s.sum(jac[:, :, None] * jac[:, None, :])
        gradient = s.sum(jac * residual[:, None])
        diag = np.einsum("mii->mi", normal)
        ridge = 1e-14 * diag.sum(axis=1, keepdims=True)
        damped = normal + np.eye(3) * (lam[:, None] * diag + ridge)[:, :, None]
        step = -np.linalg.solve(damped, gradient[:, :, None])[:, :, 0]
        trial = params + step
        trial_residual, trial_jac = _line_model(s, trial, k2, centre)
        trial_cost = s.sum(trial_residual**2)
        better = trial_cost < cost
        params = np.where(better[:, None], trial, params)
        keep = better[s.ids]
        residual = np.where(keep, trial_residual, residual)
        jac = np.where(keep[:, None], trial_jac, jac)
        converged = (cost - np.minimum(trial_cost, cost)) <= 1e-12 * cost + 1e-30
        cost = np.minimum(trial_cost, cost)
        lam = np.where(better, lam * 0.3, lam * 10.0)
        if np.all(converged):
            break
        done = (better & converged) | (lam > 1e12)
        if done.any():
            out[active[done]] = params[done]
            stay = ~done
            point_stay = stay[s.ids]
            s = s.subset(stay)
            params, lam, cost, active = params[stay], lam[stay], cost[stay], active[stay]
            residual, jac = residual[point_stay], jac[point_stay]
            if active.size == 0:
                break
    out[active] = params
    return out


def fit_lines(
    lines_norm: Sequence[np.ndarray],
    scale_px: float,
    *,
    k2: float = 0.0,
    centre: Sequence[float] = (0.0, 0.0),
    k1_start: float = 0.0,
) -> list[LineK1]:
    """Joint ``k1`` + line fit of many lines, each independently, vectorised.

    Each line gets its own ``(k1, theta, rho)`` minimising the squared
    perpendicular distances of its undistorted points to the line; ``k2``
    and the centre of distortion are held fixed.

    Parameters
    ----------
    lines_norm : sequence of ndarray, each shape (N_j, 2), N_j >= 4
        Distorted points of each line, normalised, ordered along the line.
    scale_px : float
        Pixels per normalised unit (:func:`.geometry.norm_scale`).
    k2 : float
        Fixed second radial coefficient.
    centre : array_like, shape (2,)
        Fixed centre of distortion, normalised.
    k1_start : float
        Starting value of every line's ``k1``.

    Returns
    -------
    list of LineK1

    Notes
    -----
    The model is the paper's eq. (1), ``r_u = r_d (1 + k1 r_d^2 + k2 r_d^4)``
    about the centre of distortion, with the undistorted line
    ``x cos(theta) + y sin(theta) = rho`` fitted together with ``k1``
    (Levenberg-Marquardt), rather than fixed beforehand as in the paper's
    eqs. (8)-(10); [2]_ fits lines and distortion jointly the same way.

    References
    ----------
    .. [1] H. R. Chennamma, L. Rangarajan, Image splicing detection using
       inherent lens radial distortion, IJCSI 7(6), 2010, eqs. (1), (6)-(10).
    .. [2] F. Devernay, O. Faugeras, Straight lines have to be straight,
       Machine Vision and Applications 13, 2001.

    Examples
    --------
    The bowed line of :func:`k1_paper`'s example gives back its ``k1``:

    >>> from forensics_plugins.lens_distortion.geometry import distort
    >>> x = np.linspace(-0.6, 0.6, 200)
    >>> bowed = distort(np.column_stack((x, np.full_like(x, 0.5))), k1=0.1)
    >>> (line,) = fit_lines([bowed], scale_px=500.0)
    >>> round(line.k1, 4), line.n_points
    (0.1, 200)
    """
    s = _Stacked.of(lines_norm)
    c = np.asarray(centre, dtype=np.float64)
    params = _levenberg_marquardt(s, _initial_lines(s, np.full(s.counts.size, k1_start)), k2, c)
    return _line_fits(s, params, k2, c, scale_px)


def _line_fits(s: _Stacked, params: np.ndarray, k2: float, c: np.ndarray, scale_px: float) -> list[LineK1]:
    """Each line's :class:`LineK1` at its fitted ``(k1, theta, rho)``, ``params`` shape (m, 3)."""
    residual, jac = _line_model(s, params, k2, c)
    normal = s.sum(jac[:, :, None] * jac[:, None, :])
    # Schur complement: information on k1 left after the line's own (theta, rho).
    nuisance = normal[:, 1:, 1:]
    cross = normal[:, 1:, 0]
    explained = np.einsum("mi,mi->m", cross, np.linalg.solve(nuisance, cross[:, :, None])[:, :, 0])
    info = normal[:, 0, 0] - explained
    # Reference: the k1 column's squared norm if every point sat at the largest
    # possible lever arm (|n . q| = |q|), so the test does not depend on how
    # close to the centre the line passes.
    r2 = np.einsum("ij,ij->i", s.points - c, s.points - c)
    radial = info <= _RADIAL_TOLERANCE * s.sum(r2**3)
    info = np.where(radial, 0.0, info)
    dof = np.maximum(s.counts - 3, 1)
    sigma = np.sqrt(s.sum(residual**2) / dof)
    # The error of k1 rests on the noise floor; the residual reported is the one measured.
    floored = np.maximum(sigma, MIN_EDGE_NOISE_PX / scale_px)
    tau = np.array([integrated_autocorrelation(residual[a : a + n]) for a, n in zip(s.starts, s.counts)])
    with np.errstate(divide="ignore"):
        stderr_white = np.where(radial, np.inf, floored / np.sqrt(info))
    return [
        LineK1(
            k1=float(params[j, 0]),
            k1_stderr=float(stderr_white[j] * np.sqrt(tau[j])),
            k1_stderr_white=float(stderr_white[j]),
            residual_rms_px=float(sigma[j] * scale_px),
            n_points=int(s.counts[j]),
            n_effective=float(s.counts[j] / tau[j]),
            distance=signed_distance(s.points[s.starts[j] : s.starts[j] + s.counts[j]]),
            theta=float(params[j, 1]),
            rho=float(params[j, 2]),
            leverage_px=float(np.sqrt(info[j] / s.counts[j]) * scale_px),
        )
        for j in range(s.counts.size)
    ]


def k1_joint(
    points_norm: np.ndarray,
    scale_px: float,
    *,
    k2: float = 0.0,
    centre: Sequence[float] = (0.0, 0.0),
) -> LineK1:
    """Joint ``k1`` + line fit of one line (see :func:`fit_lines`).

    Parameters
    ----------
    points_norm : ndarray, shape (N, 2), N >= 4
        Distorted points, normalised, ordered along the line.
    scale_px : float
        Pixels per normalised unit, to express residuals in pixels.
    k2 : float
        Fixed second radial coefficient.
    centre : array_like, shape (2,)
        Fixed centre of distortion, normalised.

    Returns
    -------
    LineK1

    Notes
    -----
    Starts from several values of ``k1`` (:func:`fit_lines_multistart`).
    """
    return fit_lines_multistart([points_norm], scale_px, k2=k2, centre=centre)[0]


def fit_lines_multistart(
    lines_norm: Sequence[np.ndarray],
    scale_px: float,
    *,
    k2: float = 0.0,
    centre: Sequence[float] = (0.0, 0.0),
) -> list[LineK1]:
    """:func:`fit_lines` from each of several starting ``k1``, keeping each line's best fit.

    On a line that fits the model poorly (a curved object) the cost can have
    several minima, and a start at ``k1 = 0`` can stall; without a good start
    from elsewhere (a global model), try several.
    """
    s = _Stacked.of(lines_norm)
    c = np.asarray(centre, dtype=np.float64)
    # The starting line of each (its TLS fit) does not depend on the start of k1, and the statistics are
    # computed once, for each line's best fit: the same fits as separate runs, in a third of the time.
    base = _initial_lines(s, np.zeros(s.counts.size))
    runs, costs = [], []
    for start in _K1_STARTS:
        params = _levenberg_marquardt(s, np.column_stack((np.full(s.counts.size, start), base[:, 1:])), k2, c)
        cost = s.sum(_line_model(s, params, k2, c)[0] ** 2)
        runs.append(params)
        costs.append(np.where(np.isfinite(cost), cost, np.inf))
    best = np.argmin(np.stack(costs), axis=0)
    return _line_fits(s, np.stack(runs)[best, np.arange(best.size)], k2, c, scale_px)
