"""Copies of smooth areas, found by their grain: where keypoints cannot see.

A clone tool drawn over sky, a wall, skin or a suit copies what little such an
area holds: its sensor noise. SIFT finds no keypoints there, but the grain
itself repeats. Write ``r_n`` for the residual of a 3 x 3 median filter
(:func:`.identity.residual`) divided by its local RMS over a window, so that
every smooth area counts by its size and not by its contrast. A region of
area ``a`` copied by a move ``t`` makes the autocorrelation

    A(t) = sum_p r_n(p) r_n(p + t)

reach about ``rho a`` at the move (``rho`` the copy's fidelity after the
final compression), whereas at any other lag ``A`` is a sum of ``N``
products of independent noise with spread about ``sqrt(N)``. A scene does not
repeat the noise of its smooth areas, so a sharp peak of ``A`` away from the
origin marks a candidate copy, found by FFT over every lag at once [1]_, [2]_.

Three things other than a copy also raise ``A``, and are kept out:

* **Structure.** A printed or manufactured pattern (a ruler's ticks, text,
  tiles) repeats its fine detail too. Only *smooth* windows enter: those
  whose grey-level spread is below ``smooth_ratio`` times the photo's grain
  level (the lower quartile of the windows' residual RMS). Measured on the
  shared real corpus: with every window, the ticks of a ColorChecker's ruler
  and other printed charts gave candidates whose grain peak (the test of
  :mod:`.identity`) exceeded 0.2 on 8 of 33 authentic chart photos; with
  smooth windows only, on none of the 217 authentic photos. Textured copies
  are left to the keypoints.
* **Anisotropy.** Grain that is correlated along one direction (row noise,
  a smooth area's faint streaks) correlates along a whole line of lags
  through the origin, a ridge rather than a peak. Each lag's sharpness is
  ``A(t)`` less the largest ``A`` two pixels away, which a ridge cancels and
  a copy's isolated peak keeps.
* **The JPEG grid.** Blocking repeats every 8 pixels, so the lags that are
  multiples of 8 in both directions are not searched; a copy moved by whole
  blocks is left to the keypoints.

A candidate is a lag whose sharpness stands ``min_sigma`` robust spreads
above the sharpness of all lags; the ``max_candidates`` strongest are
examined. Its copied area is where the local correlation of ``r_n(p)`` with
``r_n(p + t)`` over a window exceeds ``threshold``, largest connected part,
and it enters the same grain test as the keypoints' candidates. Only moves
(no rotation or scaling) are searched, and only moves of less than half the
work image's width and height.

References
----------
.. [1] J. Fridrich, D. Soukal, J. Lukáš, Detection of copy-move forgery in
   digital images, Digital Forensic Research Workshop, 2003 (a shift shared
   by many matching blocks).
.. [2] D. Cozzolino, G. Poggi, L. Verdoliva, Efficient dense-field copy-move
   forgery detection, IEEE TIFS 10(11), 2015.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import scipy.fft as sfft

from .identity import MIN_GRAIN
from .transforms import Hypothesis

# Lags whose sharpness is compared (a ring two pixels from the lag): a copy's
# grain decorrelates within a pixel or two, a ridge of A does not.
_RING = np.ones((5, 5), np.uint8)
_RING[1:4, 1:4] = 0
_PEAK = np.ones((5, 5), np.uint8)
_JPEG_BLOCK = 8


@dataclass(frozen=True)
class DenseCandidate:
    """A move along which a smooth area's grain repeats.

    Attributes
    ----------
    hypothesis : Hypothesis
        The move as a transform; ``source`` and ``target`` are the convex
        hull of the copied area and its image, work-image pixels.
    sigma : float
        The lag's sharpness in robust spreads of all lags' sharpness.
    area_px : int
        Pixels of the copied area (local correlation above the threshold).
    """

    hypothesis: Hypothesis
    sigma: float
    area_px: int


def _normalised_grain(gray: np.ndarray, grain: np.ndarray, window: int, smooth_ratio: float) -> np.ndarray:
    """``r_n`` of the module docstring on the smooth windows, 0 elsewhere, float32, shape as ``gray``."""
    # In place where it can be: the detector runs in a fresh child, where
    # every new array's pages cost a fault (a tenth of a second here on 2 MP).
    r = np.asarray(grain, dtype=np.float32)
    g = np.asarray(gray, dtype=np.float32)
    box = (window, window)
    rms = cv2.boxFilter(r * r, -1, box)
    np.sqrt(np.maximum(rms, 0.0, out=rms), out=rms)
    mean = cv2.boxFilter(g, -1, box)
    spread = cv2.boxFilter(g * g, -1, box)
    spread -= np.square(mean, out=mean)
    np.sqrt(np.maximum(spread, 0.0, out=spread), out=spread)
    grainy = rms > MIN_GRAIN
    if not grainy.any():
        return np.zeros_like(r)
    level = float(np.percentile(rms[grainy], 25))
    smooth = grainy & (spread < smooth_ratio * level)
    # Clipped so that a few outlying pixels (a speck, a hot pixel) cannot carry a window.
    out = np.divide(r, np.maximum(rms, 1e-6, out=rms), out=spread)
    np.clip(out, -3.0, 3.0, out=out)
    out[~smooth] = 0.0
    return out


def _sharpness(rn: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sharpness of ``A`` at the lags ``dy >= 0``, those lags (rows, columns) and the ones not searched.

    ``A(t) = A(-t)``, so half the lags hold every move; the arrays cover the
    rows ``0 <= dy < h / 2`` of the FFT grid and all its columns.
    """
    h, w = rn.shape
    # Half the size again as padding: lags up to half the image wrap onto no other lag.
    shape = (sfft.next_fast_len(h + h // 2, real=True), sfft.next_fast_len(w + w // 2, real=True))
    spectrum = sfft.rfft2(rn, s=shape, workers=1)
    power = np.square(spectrum.real)
    power += np.square(spectrum.imag)
    auto = sfft.irfft2(power, s=shape, workers=1).astype(np.float32, copy=False)
    ring = cv2.dilate(auto[: h // 2 + 2], _RING, borderType=cv2.BORDER_REFLECT)[: h // 2]
    sharp = auto[: h // 2] - ring
    dy = np.arange(h // 2)
    dx = np.fft.fftfreq(shape[1], 1.0 / shape[1]).astype(int)
    return sharp, dy, dx, ~_searched(dy, dx, h, w)


def _searched(dy: np.ndarray, dx: np.ndarray, h: int, w: int) -> np.ndarray:
    """Lags searched, boolean (rows, columns): one of each pair ``+-t``, within half the image, off the JPEG grid."""
    ry, rx = dy[:, None], dx[None, :]
    half = (ry > 0) | ((ry == 0) & (rx > 0))
    inside = (np.abs(ry) < h // 2) & (np.abs(rx) < w // 2)
    grid = (ry % _JPEG_BLOCK == 0) & (rx % _JPEG_BLOCK == 0)
    return half & inside & ~grid


def _copied_area(rn: np.ndarray, ty: int, tx: int, window: int, threshold: float) -> tuple[np.ndarray, int] | None:
    """Pixels ``(x, y)`` of the largest area whose grain correlates with its image under the move, and their count."""
    h, w = rn.shape
    y0, y1, x0, x1 = max(0, -ty), min(h, h - ty), max(0, -tx), min(w, w - tx)
    local = cv2.boxFilter(rn[y0:y1, x0:x1] * rn[y0 + ty: y1 + ty, x0 + tx: x1 + tx], -1, (window, window))
    n, labels, stats, _ = cv2.connectedComponentsWithStats((local > threshold).astype(np.uint8), connectivity=8)
    if n <= 1:
        return None
    best = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    area = int(stats[best, cv2.CC_STAT_AREA])
    if area < window * window:
        return None
    ys, xs = np.nonzero(labels == best)
    return np.column_stack((xs + x0, ys + y0)).astype(np.float32), area


def translations(gray: np.ndarray, grain: np.ndarray, *, window: int, min_distance: float, smooth_ratio: float,
                 min_sigma: float, threshold: float, max_candidates: int) -> list[DenseCandidate]:
    """Moves along which the grain of a smooth area repeats, strongest first.

    Parameters
    ----------
    gray : ndarray, shape (h, w)
        Work image, 0-255.
    grain : ndarray, shape (h, w)
        Its :func:`.identity.residual`.
    window : int
        Side of the windows of local RMS, spread and correlation, pixels.
    min_distance : float
        Moves shorter than this (pixels) are not searched.
    smooth_ratio : float
        A window is smooth when its grey-level spread is below this times the
        photo's grain level.
    min_sigma : float
        Sharpness a lag needs, in robust spreads over all lags searched.
    threshold : float
        Local correlation that marks the copied area.
    max_candidates : int
        Most moves examined (the sharpest).

    Returns
    -------
    list of DenseCandidate
    """
    rn = _normalised_grain(gray, grain, window, smooth_ratio)
    # A copy and its source each need a window's area of smooth grain.
    if np.count_nonzero(rn) < 2 * window * window:
        return []
    sharp, dy, dx, excluded = _sharpness(rn)
    rows, cols = np.flatnonzero(dy < min_distance), np.flatnonzero(np.abs(dx) < min_distance)
    excluded[np.ix_(rows, cols)] |= np.hypot(dy[rows, None], dx[None, cols]) < min_distance
    values = sharp[~excluded]
    centre = float(np.median(values))
    spread = 1.4826 * float(np.median(np.abs(values - centre)))
    if not spread > 0:
        return []
    z = (sharp - centre) / spread
    z[excluded] = -np.inf
    peaks = (z >= cv2.dilate(z, _PEAK, borderType=cv2.BORDER_REFLECT)) & (z > min_sigma)
    rows, cols = np.nonzero(peaks)
    out: list[DenseCandidate] = []
    for i in np.argsort(-z[rows, cols])[:max_candidates]:
        ty, tx = int(dy[rows[i]]), int(dx[cols[i]])
        found = _copied_area(rn, ty, tx, window, threshold)
        if found is None:
            continue
        points, area = found
        hull = cv2.convexHull(points).reshape(-1, 2).astype(np.float64)
        move = np.array([[1.0, 0.0, tx], [0.0, 1.0, ty]])
        out.append(DenseCandidate(Hypothesis(move, hull, hull + (tx, ty)), float(z[rows[i], cols[i]]), area))
    return out
