"""Is the fine grain of two matched regions the same? What tells a copy from a scene that repeats itself.

Two places of a real scene can look alike (the windows of a facade, tiles, a
balustrade) and keypoints match them as readily as a copy. What a scene does
not repeat is its fine grain: the sensor noise and the texture below the
scale of its structure are independent from one place to another, whereas a
copy carries its source's grain along, up to the resampling of a rotation or
scaling and the final compression. The grain is the residual of a 3 x 3
median filter, compared window by window (``w x w`` pixels of the target
region) with the residual of the source region mapped onto it by the
transform.

The residual also holds the edges of the structure, and a repeated structure
aligned to the pixel correlates through them: on the shared authentic real
photos the plain correlation reached 0.5 to 0.7 on gables, periodic glazing
and printed patterns, as high as many copies. What separates the two is the
*shape* of the correlation around the alignment. Write ``T`` for the
target's residual, ``M`` for the mapped source's, and ``s`` for a shift of
one pixel. A copy shares both structure and noise, so its cross-correlation
follows the target's own autocorrelation, ``C(s) = rho A(s)`` with ``rho``
the copy's fidelity. A repeated structure shares only the structure ``S``,
``C(s) = R_S(s)``; an edge's residual is a ridge along the edge, so it keeps
its correlation when shifted along it, ``R_S(s) ~ R_S(0)``. Each window's
*grain peak* is therefore

    g = (C(0) - C(s*)) / (1 - A(s*)),    s* = argmax over the 8 shifts of C(s),

the drop of the cross-correlation one pixel away in the direction where it
persists most, relative to the drop of the target's own grain there (the
denominator is held at 0.1 or more). A copy gives ``g ~ rho`` whether its
grain is white or smoothed by resampling; a repeated structure ``g ~ 0``.
The statistic is the median of ``g`` over the windows, so that a few windows
cannot carry it. Windows without grain on either side (a flat area the
compression left smooth) carry no evidence either way and are left out.

Measured on the shared real corpus (downscaled to 2 MP, each transform also
aligned on the intensities, :func:`.transforms.refine`, and compared both
ways round), the largest grain peak of a photo exceeded 0.2 on 6 of 217
authentic photos (an IMD "original" whose ground was itself cloned, the
branches of an artificial fir (or a clone of them), a printed wallpaper twice, as one file is in
the set under two names, framed prints of one photo at two sizes, and a
column of identical windows seen at two depths) and
on 107 of 110 MICC-F220 copy-moves; compared one way only, on 4 and 99. The
plain median correlation exceeded 0.2 on 20 authentic photos and 107
copy-moves.

Printed or manufactured repetition (two prints of one poster, identical
products, wallpaper) shares its fine grain too where the camera's own noise
is weak. A pattern that goes on under the same transform is told from a copy
by :mod:`.lattice`; the rest is not. The statistic is therefore not turned
into a p-value: its strength is the likelihood ratio calibrated on real
photos (:mod:`forensics_core.calibration`), whose authentic photos include
real repetition.

Why not a residual that keeps the sensor noise alone: an adaptive Wiener
residual (the structure damped by the local signal-to-noise ratio), measured
on the same corpus, takes the wallpaper, the facades and I36 below 0.1, but
also 83 of the 110 MICC-F220 copies, whose noise their compression removed.
What a compressed copy shares is its texture below the scale of its
structure, as a print does. With at most five authentic photos above the
threshold it found 27 of the MICC copies, against 105 for the median
residual.

Why not the colour channels' sub-pixel offsets: a copy carries its source's
lateral chromatic aberration along, whereas a second print or moulding in the
scene is seen through another part of the lens, so the red and blue
channels' offsets from the green would differ between the two regions only
for repetition in the scene. Measured on the shared real corpus (offsets by
least squares over each window, of the target and of the source mapped onto
it), they differed by 0.21 px between the framed prints above, by at most
0.11 px in 107 MICC-F220 copies, but by 0.24-0.36 px in 2 of the 8 IMD
copies found: a copy edited after it was pasted (recoloured, blurred,
sharpened) need not keep them, so the test would give up copies for one
false alarm.

References
----------
.. [1] I. Amerini, L. Ballan, R. Caldelli, A. Del Bimbo, G. Serra, A SIFT-based
   forensic method for copy-move attack detection and transformation recovery,
   IEEE TIFS 6(3), 2011.
.. [2] D. Cozzolino, G. Poggi, L. Verdoliva, Efficient dense-field copy-move
   forgery detection, IEEE TIFS 10(11), 2015 (the copy's dense correspondence,
   here verified on the residual rather than on the image).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from scipy import ndimage

from .transforms import Hypothesis, refine

# Residual standard deviation (grey levels) below which a window holds no
# grain to compare: JPEG leaves smooth areas with less than this.
MIN_GRAIN = 0.5
# Floor of the own grain's drop 1 - A(s*): a window smooth along s* would
# otherwise turn a small difference of correlations into a large peak.
_MIN_DROP = 0.1
_SHIFTS = tuple((dx, dy) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dx, dy) != (0, 0))


def residual(gray: np.ndarray) -> np.ndarray:
    """Fine grain: the image minus its 3 x 3 median, shape as ``gray``, float32.

    The border is replicated. OpenCV's median of float32 images, exact like
    any median, gives the same values as ``scipy.ndimage.median_filter``
    (whose "reflect" border is the same replication for a 3 x 3 window) in a
    hundredth of the time.
    """
    gray = np.ascontiguousarray(gray, dtype=np.float32)
    return gray - cv2.medianBlur(gray, 3)


@dataclass(frozen=True)
class Identity:
    """The fine-grain comparison of one hypothesis.

    Attributes
    ----------
    median : float
        Median over windows of the residual correlation ``C(0)``, in [-1, 1].
    peak : float
        Median over windows of the grain peak ``g`` (module docstring): near
        the copy's fidelity for a copy, near 0 for a repeated structure.
    windows : ndarray, shape (k, 4)
        ``(x0, y0, C(0), g)`` of each compared window of the target region:
        top-left corner (work-image pixels), correlation and grain peak.
    window : int
        Window side, work-image pixels.
    """

    median: float
    peak: float
    windows: np.ndarray
    window: int


def target_region(hypothesis: Hypothesis, shape: tuple[int, int], margin: int) -> np.ndarray:
    """The convex hull of the target keypoints grown by ``margin`` pixels, boolean, shape ``shape``."""
    hull = cv2.convexHull(hypothesis.target.astype(np.float32)).astype(np.int32)
    region = np.zeros(shape, np.uint8)
    cv2.fillConvexPoly(region, hull, 1)
    if margin > 0:
        region = cv2.dilate(region, np.ones((2 * margin + 1, 2 * margin + 1), np.uint8))
    return region.astype(bool)


def _shifted(a: np.ndarray, dx: int, dy: int) -> np.ndarray:
    """``a`` without its one-pixel border, read ``(dx, dy)`` pixels away: shape ``(h - 2, w - 2)``."""
    return a[1 + dy: a.shape[0] - 1 + dy, 1 + dx: a.shape[1] - 1 + dx]


def identity(gray: np.ndarray, grain: np.ndarray, hypothesis: Hypothesis, window: int,
             min_offset_px: float) -> Identity | None:
    """Compare the fine grain of a hypothesis' target region with its source's.

    Parameters
    ----------
    gray : ndarray, shape (h, w)
        Work image, 0-255.
    grain : ndarray, shape (h, w)
        :func:`residual` of ``gray``.
    hypothesis : Hypothesis
    window : int
        Window side, pixels.
    min_offset_px : float
        Pixels closer than this to their own source are left out (near the
        fixed point of a rotation or scaling a region is compared with
        itself).

    Returns
    -------
    Identity or None
        None when fewer than four windows hold grain on both sides.
    """
    h, w = gray.shape
    region = target_region(hypothesis, (h, w), window)
    ys, xs = np.nonzero(region)
    if len(xs) == 0:
        return None
    # Only the target region's box (on the window grid, with a margin for the
    # median filter, the erosion and the one-pixel shifts) is warped and
    # compared, so the cost follows the region's size, not the photo's.
    margin = 5
    x0 = max(0, (int(xs.min()) - margin) // window * window)
    y0 = max(0, (int(ys.min()) - margin) // window * window)
    x1, y1 = min(w, int(xs.max()) + 1 + margin), min(h, int(ys.max()) + 1 + margin)
    shifted = hypothesis.matrix.copy()
    shifted[:, 2] -= (x0, y0)
    warped = cv2.warpAffine(gray, shifted, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_CONSTANT, borderValue=np.nan)
    inside = ndimage.binary_erosion(np.isfinite(warped), iterations=3, border_value=1)
    moved = residual(np.nan_to_num(warped))
    back = cv2.invertAffineTransform(hypothesis.matrix)
    yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float32)
    sx = back[0, 0] * xx + back[0, 1] * yy + back[0, 2]
    sy = back[1, 0] * xx + back[1, 1] * yy + back[1, 2]
    usable = _shifted(region[y0:y1, x0:x1] & inside & (np.hypot(sx - xx, sy - yy) >= min_offset_px), 0, 0)
    own = grain[y0:y1, x0:x1]
    nh, nw = usable.shape[0] // window, usable.shape[1] // window

    def tiles(a: np.ndarray) -> np.ndarray:
        return a[: nh * window, : nw * window].reshape(nh, window, nw, window).swapaxes(1, 2).reshape(
            nh, nw, window * window)

    full = tiles(usable).all(axis=-1)

    def centred(a: np.ndarray) -> np.ndarray:
        t = tiles(a)[full].astype(np.float64)
        return t - t.mean(axis=1, keepdims=True)

    def corr(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        energy = np.einsum("ij,ij->i", a, a) * np.einsum("ij,ij->i", b, b)
        return np.einsum("ij,ij->i", a, b) / np.sqrt(np.maximum(energy, 1e-12))

    a, b = centred(_shifted(own, 0, 0)), centred(_shifted(moved, 0, 0))
    grainy = (a.std(axis=1) > MIN_GRAIN) & (b.std(axis=1) > MIN_GRAIN)
    if grainy.sum() < 4:
        return None
    a, b = a[grainy], b[grainy]
    r = corr(a, b)
    cross = np.stack([corr(a, centred(_shifted(moved, dx, dy))[grainy]) for dx, dy in _SHIFTS])
    own_auto = np.stack([corr(a, centred(_shifted(own, dx, dy))[grainy]) for dx, dy in _SHIFTS])
    along = cross.argmax(axis=0)
    k = np.arange(len(r))
    g = (r - cross[along, k]) / np.maximum(1.0 - own_auto[along, k], _MIN_DROP)
    rows, cols = np.nonzero(full)
    corners = np.column_stack((x0 + 1 + cols[grainy] * window, y0 + 1 + rows[grainy] * window, r, g))
    return Identity(float(np.median(r)), float(np.median(g)), corners, window)


def best_alignment(gray: np.ndarray, grain: np.ndarray, h: Hypothesis,
                   params: Mapping[str, Any]) -> tuple[Hypothesis, Identity | None, str]:
    """The hypothesis, either way round, at the alignment (keypoints' or refined on intensities) where the grain
    peak is highest.

    Which region is the copy is unknown, and the comparison is not symmetric:
    the source is resampled onto the target, so only warping the source onto
    its copy repeats the resampling the copy went through. On the shared
    MICC-F220 copy-moves the better of the two directions raised the grain
    peak of rotated and scaled copies (median 0.41 to 0.44; above 0.3 on 101
    of 110 copies instead of 84).
    """
    window, offset = int(params["window_px"]), float(params["min_distance_px"])
    best, found, how = h, None, "keypoints"
    for way in (h, h.reversed()):
        refined = refine(gray, way, target_region(way, gray.shape, 0), float(params["refine_max_shift_px"]))
        for candidate, aligned in ((way, "keypoints"), (refined, "intensities (ECC)")):
            if candidate is None:
                continue
            again = identity(gray, grain, candidate, window, offset)
            if again is not None and (found is None or again.peak > found.peak):
                best, found, how = candidate, again, aligned
    return best, found, how
