r"""A mosaic that drifts smoothly across the photo: the whole frame resampled slightly after demosaicing.

A camera that scales its demosaiced sensor image to the output size by a
fraction of a percent, or an editor's slight resize, rotation or shear,
moves the content at every pixel by a displacement ``d(x, y)`` that varies
linearly across the frame. The demosaicing trace is periodic with period 2,
so after resampling each block keeps the camera's trace shifted by ``round(d)``
along each axis, weakened by the interpolation as the fractional part of
``d`` nears one half (where two phases are averaged and none survives). Such
a photo shows broad bands of other phases, one pixel of displacement apart,
and a scan against the photo's one phase reports the band at a corner as a
pasted region of another mosaic. Measured on the real corpus's Olympus E-10
original: its votes put green on the other diagonal in the bottom-right
corner and red and blue swapped at the top right, and an affine drift of
about 1.5 px across its width and 0.5 px down its height explains them far
better than one phase (a gain of 530 nats in log-likelihood).

Model. For each axis the block's parity vote ``c = +1`` (even) or ``-1``
(odd) follows

.. math::  P(c) = \tfrac12 \left(1 + A\, c\, S_\kappa(a_0 + a_1 u + a_2 v)\right),
           \qquad S_\kappa(d) = \tanh(\kappa \cos \pi d) / \tanh \kappa,

with ``(u, v)`` the block centre in units of half the larger side about the
frame's centre, ``A`` the trace's strength and ``kappa`` how abruptly the
phase changes (near 0 the cosine of interpolation, large the square wave of
nearest-neighbour resampling); one phase throughout is ``a_1 = a_2 = 0``.
The slopes are searched on a grid (the linear score
``|sum c exp(i pi (a_1 u + a_2 v))|``, a matrix product, gives each pair's
best offset in closed form) and the best few refined by maximum likelihood.

Test. A region the plain scan flagged is explained by a drift when the drift
fitted to the votes *outside* it explains those votes better than one phase
by at least :data:`MIN_OUTSIDE_GAIN` nats and puts blocks there in the other
parity that vote so (:data:`MAX_FLIP_LOG10_P`): the rest of the photo shows
the drift and a phase change it makes by itself, so a paste cannot make the
drift that would explain it, nor can a profile that only follows where the
trace is weak or strong;
extrapolated into the region accounts for at least :data:`MIN_EXPLAINED` of
its votes' departure from the photo's phase, and the region has a band's
shape: a drift's bands are stripes between parallel lines, so each reaches
two borders of the frame, and covers at most :data:`MAX_EXPLAINED_SHARE` of
the votes (:class:`DriftCheck`). Its blocks then abstain and the scan is run
again. A piece pasted away from the borders, or in another phase than the
drift predicts where it lies, is still found; one pasted at a corner in the
phase the drift predicts there is not, the price of naming this processing.
Measured: on the real corpus's Olympus E-10 original the drift fitted around
its one flagged corner gains 390 nats over one phase and predicts 109 of the
corner's 153 nats of departure; a piece moved within that photo away from
its borders, whose phase happened to match the drift's, was explained before
the border rule and is found with it.

References
----------
.. [1] A. C. Popescu, H. Farid, Exposing digital forgeries in color filter
   array interpolated images, IEEE Trans. Signal Processing 53(10), 2005
   (the period-2 trace of demosaicing).
.. [2] M. Kirchner, Fast and reliable resampling detection by spectral
   analysis of fixed linear predictor residue, ACM MM&Sec 2008 (resampling
   moves and attenuates periodic traces).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from .significance import log10_binom_tail

#: Slopes searched on each axis, pixels of displacement per half the larger side.
SLOPES = np.arange(-2.5, 2.5 + 1e-9, 0.0625)
#: Outside the region, the drift must put blocks decisively in the other parity (its profile at most -1/2 there)
#: and their votes must confirm it: more odd than even votes, binomial tail at most this (log10), on one axis.
MAX_FLIP_LOG10_P = -3.0
#: Least log-likelihood gain (nats) of the drift over one phase on the votes outside the region: the rest of the
#: photo must show the drift by itself. The slope grids hold 81^2 pairs per axis, about 13 000 choices: a gain of
#: 30 nats is a likelihood ratio of 1e13, which the search alone does not make (1e13 / 1.3e4 = 1e9).
MIN_OUTSIDE_GAIN = 30.0
#: Least share of a region's departure from the photo's phase (in log-likelihood) the drift must predict.
MIN_EXPLAINED = 0.5
#: Largest share of the voting blocks a drift may explain: where regions of other phases cover more, the photo's
#: own phase is in doubt and no region is set aside.
MAX_EXPLAINED_SHARE = 0.25
#: A region reaches a border when its blocks come this close to it, as a share of the frame's side: the blocks
#: along the borders often abstain (clipped sky, flat ground), and the band a drift makes ends where it crosses
#: half a pixel, not at a block's edge.
BORDER_MARGIN = 0.08
#: Voting blocks the fit reads at most (evenly spread), to bound its time on large photos.
MAX_BLOCKS = 8000
#: Grid candidates per axis refined by maximum likelihood.
_REFINED = 4
#: Sharpness of the trace's profile tried (:func:`_shape`): from interpolation's cosine to nearest-neighbour's
#: square wave.
SHARPNESS = (0.05, 3.0)
_MAX_STRENGTH = 0.99


@dataclass(frozen=True)
class AffineDrift:
    """A displacement of the whole photo that varies linearly across it.

    ``dx = a0 + a1 u + a2 v`` and ``dy = b0 + b1 u + b2 v`` pixels, with
    ``u = (x - cx) / s`` and ``v = (y - cy) / s`` for the centre
    ``(cx, cy) = ((W - 1) / 2, (H - 1) / 2)`` and ``s`` half the larger side.

    Attributes
    ----------
    dx, dy : tuple of 3 float
        The terms of each axis, pixels.
    """

    dx: tuple[float, float, float]
    dy: tuple[float, float, float]

    def displacement(self, y: np.ndarray, x: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """``(dy, dx)``, pixels, at rows ``y`` and columns ``x`` (broadcast together) of a ``(H, W)`` grid."""
        u, v = _normalised(np.asarray(y, dtype=np.float64), np.asarray(x, dtype=np.float64), shape)
        return self.dy[0] + self.dy[1] * u + self.dy[2] * v, self.dx[0] + self.dx[1] * u + self.dx[2] * v

    def spans_px(self, shape: tuple[int, int]) -> tuple[float, float]:
        """How much ``dy`` and ``dx`` change between the frame's corners, pixels."""
        h, w = shape
        dy, dx = self.displacement(np.array([0.0, 0.0, h - 1.0, h - 1.0]), np.array([0.0, w - 1.0, 0.0, w - 1.0]),
                                   shape)
        return float(np.ptp(dy)), float(np.ptp(dx))


@dataclass(frozen=True)
class DriftFit:
    """The affine drift that best explains the blocks' phase votes, and how much better than one phase.

    Attributes
    ----------
    drift : AffineDrift
    gain : float
        Log-likelihood gain over one phase throughout, nats, both axes.
    strength : (float, float)
        ``A`` of the y and x axes.
    sharpness : (float, float)
        The profile's sharpness on each axis (:func:`_shape`).
    n_blocks : int
        Votes read.
    """

    drift: AffineDrift
    gain: float
    strength: tuple[float, float]
    sharpness: tuple[float, float]
    n_blocks: int

    def log_likelihood(self, shift_vote: np.ndarray, blocks: np.ndarray, block: int, shape: tuple[int, int],
                       drifted: bool = True) -> float:
        """Log-likelihood of the votes of ``blocks`` (boolean, shape (ny, nx)) under the drift, nats.

        With ``drifted=False``, under the photo's one phase at the same strengths.
        """
        ys, xs = np.nonzero(blocks & (shift_vote >= 0))
        if ys.size == 0:
            return 0.0
        dy, dx = self.drift.displacement(ys * block + (block - 1) / 2.0, xs * block + (block - 1) / 2.0, shape)
        vote = shift_vote[ys, xs]
        total = 0.0
        for d, odd, strength, sharpness in ((dy, np.isin(vote, (2, 3)), self.strength[0], self.sharpness[0]),
                                            (dx, np.isin(vote, (1, 3)), self.strength[1], self.sharpness[1])):
            phase = _shape(d, sharpness) if drifted else 1.0
            total += float(np.sum(np.log1p(strength * np.where(odd, -1.0, 1.0) * phase)) - ys.size * np.log(2.0))
        return total


    def flip_log10_p(self, shift_vote: np.ndarray, blocks: np.ndarray, block: int, shape: tuple[int, int]) -> float:
        """The smaller over the two axes of log10 P(Bin(n, 1/2) >= k): ``k`` odd votes among the ``n`` blocks of
        ``blocks`` that the drift puts decisively in the other parity (profile at most -1/2); 0 where there are none."""
        ys, xs = np.nonzero(blocks & (shift_vote >= 0))
        dy, dx = self.drift.displacement(ys * block + (block - 1) / 2.0, xs * block + (block - 1) / 2.0, shape)
        best = 0.0
        for d, odd, sharpness in zip((dy, dx), _parities(shift_vote, ys, xs), self.sharpness):
            flipped = _shape(d, sharpness) <= -0.5
            n = int(flipped.sum())
            if n:
                best = min(best, float(log10_binom_tail(np.array([int(odd[flipped].sum())]), np.array([n]), 0.5)[0]))
        return best


@dataclass(frozen=True)
class DriftCheck:
    """Whether the drift the rest of the photo shows predicts a region of another phase.

    Attributes
    ----------
    fit : DriftFit
        Fitted to every voting block outside the region.
    outside_gain : float
        The gain of ``fit`` over one phase on those blocks, nats: the drift
        the rest of the photo shows by itself.
    region_gain : float
        The region's votes under the drift, extrapolated into it, minus
        under the photo's one phase, nats.
    own_gain : float
        The region's votes in a phase of its own (each axis's majority
        parity at its best strength) minus under the photo's one phase,
        nats: the departure to be explained.
    share : float
        The region's share of the voting blocks.
    span_px : float
        The largest change of the drift's displacement across the frame on either axis, pixels.
    flip_log10_p : float
        Outside the region, on the axis where it is smallest: log10 of the
        binomial tail (fair coin) of the odd votes of the blocks the drift
        puts decisively in the other parity; 0 where it puts none. A phase
        change the votes confirm, which a drift that only follows where the
        trace is weak or strong (its profile between 1 and 0) cannot show.
    borders : int
        How many of the frame's four borders the region reaches (within :data:`BORDER_MARGIN`).
    """

    fit: DriftFit
    outside_gain: float
    region_gain: float
    own_gain: float
    share: float
    span_px: float
    flip_log10_p: float
    borders: int

    @property
    def explained(self) -> bool:
        """The rest of the photo shows a drift (:data:`MIN_OUTSIDE_GAIN`) and a phase change it makes
        (:data:`MAX_FLIP_LOG10_P`), the drift predicts at least :data:`MIN_EXPLAINED` of the region's departure, and
        the region is shaped as a drift's band is: it reaches two of the frame's borders and holds at most
        :data:`MAX_EXPLAINED_SHARE` of the votes."""
        return (self.flip_log10_p <= MAX_FLIP_LOG10_P and self.outside_gain >= MIN_OUTSIDE_GAIN and self.region_gain > 0.0
                and self.region_gain >= MIN_EXPLAINED * self.own_gain and self.share <= MAX_EXPLAINED_SHARE
                and self.borders >= 2)

    def record(self) -> dict[str, object]:
        d = self.fit.drift
        return {"dx_terms_px": [round(t, 3) for t in d.dx], "dy_terms_px": [round(t, 3) for t in d.dy],
                "span_px": round(self.span_px, 2), "outside_gain_nats": round(float(self.outside_gain), 1),
                "flip_log10_p": round(float(self.flip_log10_p), 2),
                "region_gain_nats": round(float(self.region_gain), 1), "own_gain_nats": round(float(self.own_gain), 1),
                "share": round(float(self.share), 4), "borders": self.borders, "explained": self.explained}


RULE = (f"an affine displacement of the whole frame is fitted by maximum likelihood to the phase votes of the blocks "
        f"outside a region; the region is explained by it when that displacement explains those votes better than one "
        f"phase by at least {MIN_OUTSIDE_GAIN:g} nats, puts some of those blocks in the other parity and their votes "
        f"confirm it (more odd than even votes, p at most 1e{MAX_FLIP_LOG10_P:g}), and, "
        f"extrapolated into the region, accounts for at least {100 * MIN_EXPLAINED:g} % of its votes' departure from "
        f"the photo's phase (log-likelihood), the region reaching two of the frame's borders, as a band of a drift "
        f"does, and holding at most {100 * MAX_EXPLAINED_SHARE:g} % of the votes")


def _normalised(y: np.ndarray, x: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    h, w = shape
    s = max(h, w) / 2.0
    return (x - (w - 1) / 2.0) / s, (y - (h - 1) / 2.0) / s


def _shape(d: np.ndarray, sharpness: float) -> np.ndarray:
    """The trace's signed strength at displacement ``d``: ``cos(pi d)`` squared off by ``sharpness``.

    Interpolation fades the trace towards half-integer displacements
    (``sharpness`` near 0: the cosine); nearest-neighbour resampling keeps
    it whole up to them (large ``sharpness``: a square wave).
    """
    return np.tanh(sharpness * np.cos(np.pi * d)) / np.tanh(sharpness)


def _log_likelihood(terms: np.ndarray, strength: float, sharpness: float, u: np.ndarray, v: np.ndarray,
                    c: np.ndarray) -> float:
    phase = _shape(terms[0] + terms[1] * u + terms[2] * v, sharpness)
    return float(np.sum(np.log1p(strength * c * phase)) - c.size * np.log(2.0))


def _one_phase(odd: np.ndarray) -> float:
    """Log-likelihood of one parity throughout at its best strength (the majority's share), nats."""
    n_odd, n = int(odd.sum()), odd.size
    return float(sum(k * np.log(k / n) for k in (n_odd, n - n_odd) if k))


def _axis(u: np.ndarray, v: np.ndarray, odd: np.ndarray) -> tuple[np.ndarray, float, float, float]:
    """The terms ``(a0, a1, a2)``, strength, sharpness and log-likelihood gain over one parity of one axis's votes."""
    c = np.where(odd, -1.0, 1.0)
    eu = np.exp(1j * np.pi * SLOPES[:, None] * u[None, :])
    ev = np.exp(1j * np.pi * SLOPES[:, None] * v[None, :])
    score = (eu * c[None, :]) @ ev.T
    flat = np.argsort(np.abs(score), axis=None)[::-1][:_REFINED]
    best = (np.zeros(3), 0.0, SHARPNESS[0], -np.inf)
    for i, j in zip(*np.unravel_index(flat, score.shape)):
        for sharpness in SHARPNESS:
            start = np.array([-np.angle(score[i, j]) / np.pi, SLOPES[i], SLOPES[j], 0.3])

            def cost(p: np.ndarray) -> float:
                return -_log_likelihood(p[:3], float(np.clip(p[3], 0.0, _MAX_STRENGTH)), sharpness, u, v, c)

            fit = minimize(cost, start, method="Nelder-Mead", options={"xatol": 1e-3, "fatol": 1e-2, "maxiter": 600})
            if -fit.fun > best[3]:
                best = (fit.x[:3], float(np.clip(fit.x[3], 0.0, _MAX_STRENGTH)), sharpness, -fit.fun)
    return best[0], best[1], best[2], best[3] - _one_phase(odd)


def _parities(shift_vote: np.ndarray, ys: np.ndarray, xs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Whether each block's voted shift is odd along y and along x."""
    vote = shift_vote[ys, xs]
    return np.isin(vote, (2, 3)), np.isin(vote, (1, 3))


def fit_drift(shift_vote: np.ndarray, voting: np.ndarray, block: int, shape: tuple[int, int]) -> DriftFit | None:
    """The affine drift of the photo's mosaic from its blocks' phase votes.

    Parameters
    ----------
    shift_vote : ndarray of int, shape (ny, nx)
        Each block's voted shift, an index into :data:`.votes.SHIFTS`
        (``(dy, dx)`` parities (0, 0), (0, 1), (1, 0), (1, 1)); negative
        where it did not vote.
    voting : ndarray of bool, shape (ny, nx)
        The blocks to read.
    block : int
        Block side, pixels.
    shape : (H, W)
        The stored grid's size, pixels.

    Returns
    -------
    DriftFit or None
        None when fewer than 64 blocks vote.
    """
    ys, xs = np.nonzero(voting & (shift_vote >= 0))
    if ys.size < 64:
        return None
    if ys.size > MAX_BLOCKS:
        pick = np.linspace(0, ys.size - 1, MAX_BLOCKS).round().astype(np.intp)
        ys, xs = ys[pick], xs[pick]
    u, v = _normalised(ys * block + (block - 1) / 2.0, xs * block + (block - 1) / 2.0, shape)
    terms, strengths, sharpness, gain = [], [], [], 0.0
    for odd in _parities(shift_vote, ys, xs):
        t, a, k, g = _axis(u, v, odd)
        terms.append(tuple(float(x) for x in t))
        strengths.append(a)
        sharpness.append(k)
        gain += g
    return DriftFit(AffineDrift(dx=terms[1], dy=terms[0]), gain, (strengths[0], strengths[1]),
                    (sharpness[0], sharpness[1]), int(ys.size))


def check_region(shift_vote: np.ndarray, voting: np.ndarray, region: np.ndarray, block: int,
                 shape: tuple[int, int]) -> DriftCheck | None:
    """Whether the drift of the blocks outside ``region`` (boolean, shape (ny, nx)) predicts its phase.

    ``shift_vote`` and ``voting`` as in :func:`fit_drift`; None when too few
    blocks outside the region vote.
    """
    blocks = voting & (shift_vote >= 0)
    fit = fit_drift(shift_vote, blocks & ~region, block, shape)
    if fit is None:
        return None
    ys, xs = np.nonzero(blocks & ~region)
    outside_gain = (fit.log_likelihood(shift_vote, blocks & ~region, block, shape)
                    - sum(_one_phase(odd) for odd in _parities(shift_vote, ys, xs)))
    one_phase = fit.log_likelihood(shift_vote, blocks & region, block, shape, drifted=False)
    region_gain = fit.log_likelihood(shift_vote, blocks & region, block, shape) - one_phase
    ys, xs = np.nonzero(blocks & region)
    own_gain = sum(_one_phase(odd) for odd in _parities(shift_vote, ys, xs)) - one_phase
    share = float(ys.size / max(int(blocks.sum()), 1))
    rows, cols = np.nonzero(region)
    ny, nx = region.shape
    my, mx = BORDER_MARGIN * ny, BORDER_MARGIN * nx
    borders = (int(rows.min(initial=ny) <= my) + int(rows.max(initial=-1) >= ny - 1 - my)
               + int(cols.min(initial=nx) <= mx) + int(cols.max(initial=-1) >= nx - 1 - mx))
    return DriftCheck(fit, outside_gain, region_gain, own_gain, share, max(fit.drift.spans_px(shape)),
                      fit.flip_log10_p(shift_vote, blocks & ~region, block, shape), borders)
