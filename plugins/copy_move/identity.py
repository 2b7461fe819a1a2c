"""Is the fine grain of two matched regions the same? What tells a copy from a scene that repeats itself.

Two places of a real scene can look alike (the windows of a facade, tiles, a
balustrade) and keypoints match them as readily as a copy. What a scene does
not repeat is its fine grain: the sensor noise and the texture below the
scale of its structure are independent from one place to another, whereas a
copy carries its source's grain along, up to the resampling of a rotation or
scaling and the final compression. The grain is the residual of a 3 x 3
median filter. For each window of ``w x w`` pixels of the target region, the
correlation between its residual and the residual of the source region mapped
onto it by the transform is computed; the statistic is their median over the
windows, so that windows where aligned structure leaks into the residual
(edges of repeated objects) cannot carry it on their own. Windows without
grain on either side (a flat area the compression left smooth) carry no
evidence either way and are left out.

Printed or manufactured repetition (two prints of one poster, identical
products, wallpaper) shares its fine grain too where the camera's own noise
is weak. The statistic is therefore not turned into a p-value: its strength
is the likelihood ratio calibrated on real photos
(:mod:`forensics_core.calibration`), whose authentic photos include real
repetition. Measured on the shared real corpus (downscaled to 2 MP), with
each transform also aligned on the intensities (:func:`.transforms.refine`):
the median correlation exceeded 0.3 on 17 of 217 authentic photos (fine
regular structure such as a glass facade's mullions, which the alignment
now matches to the pixel, a web "original" whose ground was itself cloned,
test-chart scenes) and on 107 of 110 MICC-F220 copy-moves; with keypoint
alignment alone, on 5 and 70.

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

from dataclasses import dataclass

import cv2
import numpy as np
from scipy import ndimage

from .transforms import Hypothesis

# Residual standard deviation (grey levels) below which a window holds no
# grain to compare: JPEG leaves smooth areas with less than this.
_MIN_GRAIN = 0.5


def residual(gray: np.ndarray) -> np.ndarray:
    """Fine grain: the image minus its 3 x 3 median, shape as ``gray``, float32."""
    gray = np.asarray(gray, dtype=np.float32)
    return gray - ndimage.median_filter(gray, size=3)


@dataclass(frozen=True)
class Identity:
    """The fine-grain comparison of one hypothesis.

    Attributes
    ----------
    median : float
        Median over windows of the residual correlation, in [-1, 1].
    windows : ndarray, shape (k, 3)
        ``(x0, y0, r)`` of each compared window of the target region:
        top-left corner (work-image pixels) and correlation.
    window : int
        Window side, work-image pixels.
    """

    median: float
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
    # median filter and the erosion) is warped and compared, so the cost
    # follows the region's size, not the photo's.
    margin = 4
    x0 = max(0, (int(xs.min()) - margin) // window * window)
    y0 = max(0, (int(ys.min()) - margin) // window * window)
    x1, y1 = min(w, int(xs.max()) + 1 + margin), min(h, int(ys.max()) + 1 + margin)
    shifted = hypothesis.matrix.copy()
    shifted[:, 2] -= (x0, y0)
    warped = cv2.warpAffine(gray, shifted, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_CONSTANT, borderValue=np.nan)
    inside = ndimage.binary_erosion(np.isfinite(warped), iterations=2, border_value=1)
    moved = residual(np.nan_to_num(warped))
    back = cv2.invertAffineTransform(hypothesis.matrix)
    yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float32)
    sx = back[0, 0] * xx + back[0, 1] * yy + back[0, 2]
    sy = back[1, 0] * xx + back[1, 1] * yy + back[1, 2]
    usable = region[y0:y1, x0:x1] & inside & (np.hypot(sx - xx, sy - yy) >= min_offset_px)
    own = grain[y0:y1, x0:x1]
    nh, nw = (y1 - y0) // window, (x1 - x0) // window

    def tiles(a: np.ndarray) -> np.ndarray:
        return a[: nh * window, : nw * window].reshape(nh, window, nw, window).swapaxes(1, 2).reshape(
            nh, nw, window * window)

    full = tiles(usable).all(axis=-1)
    a = tiles(own)[full].astype(np.float64)
    b = tiles(moved)[full].astype(np.float64)
    a -= a.mean(axis=1, keepdims=True)
    b -= b.mean(axis=1, keepdims=True)
    grainy = (a.std(axis=1) > _MIN_GRAIN) & (b.std(axis=1) > _MIN_GRAIN)
    if grainy.sum() < 4:
        return None
    a, b = a[grainy], b[grainy]
    r = np.einsum("ij,ij->i", a, b) / np.sqrt(np.einsum("ij,ij->i", a, a) * np.einsum("ij,ij->i", b, b))
    rows, cols = np.nonzero(full)
    corners = np.column_stack((x0 + cols[grainy] * window, y0 + rows[grainy] * window, r))
    return Identity(float(np.median(r)), corners, window)
