"""Sub-pixel edge points: Canny non-maximum suppression with Devernay's correction.

This is the first step of the paper's line-based calibration (sec. 3.3,
"Detection of edges with sub-pixel accuracy", ref. [21] = F. Devernay, "A
non-maxima suppression method for edge detection with sub-pixel accuracy",
INRIA RR-2724, 1995).

Pipeline, all vectorised over pixels:

1. Gaussian smoothing of the luma image (``sigma`` pixels).
2. Gradient by central differences; gradient norm ``|g|``.
3. Non-maximum suppression. Following Devernay (1995) the norm is compared
   with its two neighbours along the *horizontal* axis when ``|gx| >= |gy|``
   and along the *vertical* axis otherwise, not with values interpolated along
   the exact gradient direction: the norm of a blurred straight step depends
   only on the distance to the edge, so along any fixed axis it peaks exactly on
   the edge, whereas interpolating neighbours along the gradient adds a bias
   that depends on the edge orientation.
4. Devernay's sub-pixel correction: the vertex of the parabola through the
   three norm samples ``(a, m, b)`` at offsets ``(-1, 0, +1)`` along that axis,
   ``offset = (a - b) / (2 (a - 2 m + b))``, which lies in ``[-0.5, 0.5]``.
5. Hysteresis: keep 8-connected groups of maxima with ``|g| >= low`` that
   contain at least one maximum with ``|g| >= high``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

__all__ = ["EdgePoints", "auto_thresholds", "subpixel_edges"]

#: Median of a Rayleigh distribution divided by its scale, sqrt(2 ln 2).
_RAYLEIGH_MEDIAN = float(np.sqrt(2.0 * np.log(2.0)))
#: Auto thresholds in multiples of the estimated gradient-noise scale.
_LOW_NOISE_FACTOR = 4.0
_HIGH_LOW_RATIO = 2.5
#: Floors on the auto thresholds (luma units per pixel): below them an edge of a
#: nearly flat image is too weak to be localised to a fraction of a pixel.
_LOW_FLOOR = 0.01
_HIGH_FLOOR = 0.03
#: Sub-sampling step of the gradient norm when estimating the noise scale; the
#: median of a quarter-resolution grid is as good and 16 times cheaper.
_NOISE_STEP = 4


@dataclass(frozen=True)
class EdgePoints:
    """Sub-pixel edge points of an image.

    Attributes
    ----------
    xy : ndarray, shape (N, 2), float64
        Sub-pixel edge positions in pixels ``(x, y)`` = (column, row), with
        ``(0, 0)`` the centre of the top-left pixel.
    normal : ndarray, shape (N, 2), float64
        Unit gradient direction ``(gx, gy)/|g|`` at the point (points from dark
        to bright, so it encodes the edge polarity).
    strength : ndarray, shape (N,), float64
        Gradient norm at the pixel, luma units per pixel.
    pixel : ndarray, shape (N, 2), int64
        ``(row, col)`` of the pixel the point was found at; each pixel holds at
        most one point.
    low, high : float
        Hysteresis thresholds used (luma units per pixel).
    """

    xy: np.ndarray
    normal: np.ndarray
    strength: np.ndarray
    pixel: np.ndarray
    low: float = 0.0
    high: float = 0.0

    def __len__(self) -> int:
        return int(self.xy.shape[0])


def _gradient(gray: np.ndarray, sigma: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Smoothed central-difference gradient and its norm, float32, shape (H, W) each.

    float32 halves the memory traffic on multi-megapixel images; its 1e-7
    relative precision is far below the sub-pixel accuracy that matters here.
    """
    img = np.asarray(gray, dtype=np.float32)
    if sigma > 0:
        img = ndimage.gaussian_filter(img, sigma, mode="nearest")
    gx = np.zeros_like(img)
    gy = np.zeros_like(img)
    np.subtract(img[:, 2:], img[:, :-2], out=gx[:, 1:-1])
    np.subtract(img[2:, :], img[:-2, :], out=gy[1:-1, :])
    gx *= 0.5
    gy *= 0.5
    norm = np.sqrt(gx * gx + gy * gy)
    return gx, gy, norm


def auto_thresholds(norm: np.ndarray) -> tuple[float, float]:
    """Hysteresis thresholds from the distribution of the gradient norm.

    Most pixels of a photo are not on edges, and there the gradient of smoothed
    noise is a 2-D Gaussian vector whose norm is Rayleigh-distributed. The
    median of the norm (over a 1-in-4 grid of pixels) therefore estimates the
    Rayleigh scale ``s = median / sqrt(2 ln 2)``; texture only raises it, which
    errs on the side of fewer, cleaner edges. Then
    ``low = max(4 s, 0.01)`` (a Rayleigh variable exceeds ``4 s`` with
    probability ``exp(-8) ~ 3e-4``) and ``high = max(2.5 low, 0.03)``.

    Parameters
    ----------
    norm : ndarray, shape (H, W)
        Gradient norm, luma units per pixel.

    Returns
    -------
    low, high : float
        Thresholds, luma units per pixel.
    """
    scale = float(np.median(norm[::_NOISE_STEP, ::_NOISE_STEP])) / _RAYLEIGH_MEDIAN
    low = max(_LOW_NOISE_FACTOR * scale, _LOW_FLOOR)
    high = max(_HIGH_LOW_RATIO * low, _HIGH_FLOOR)
    return low, high


def _local_maxima(gx: np.ndarray, gy: np.ndarray, norm: np.ndarray, low: float):
    """Devernay non-maximum suppression on the pixels with ``norm >= low``.

    Returns
    -------
    flat : ndarray, shape (M,), int64
        Flat indices of the local maxima.
    offset : ndarray, shape (M,), float64
        Sub-pixel offset of the norm's parabola vertex, pixels, in [-0.5, 0.5].
    horizontal : ndarray, shape (M,), bool
        True where the offset is along x (``|gx| >= |gy|``), else along y.
    """
    h, w = norm.shape
    inner = np.zeros((h, w), dtype=bool)
    inner[1:-1, 1:-1] = norm[1:-1, 1:-1] >= low
    flat = np.flatnonzero(inner)
    horizontal = np.abs(gx.ravel()[flat]) >= np.abs(gy.ravel()[flat])
    step = np.where(horizontal, 1, w)
    n = norm.ravel()
    a = n[flat - step].astype(np.float64)
    m = n[flat].astype(np.float64)
    b = n[flat + step].astype(np.float64)
    # Strict on one side, loose on the other: a plateau of two equal samples
    # yields exactly one maximum.
    keep = (a < m) & (m >= b)
    flat, horizontal, a, m, b = flat[keep], horizontal[keep], a[keep], m[keep], b[keep]
    offset = 0.5 * (a - b) / (a - 2.0 * m + b)
    return flat, offset, horizontal


def _hysteresis(flat: np.ndarray, strong: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Mask over ``flat`` of the maxima 8-connected to a strong maximum."""
    mask = np.zeros(shape, dtype=bool)
    mask.ravel()[flat] = True
    labels, count = ndimage.label(mask, structure=np.ones((3, 3), dtype=bool))
    lab = labels.ravel()[flat]
    good = np.zeros(count + 1, dtype=bool)
    good[lab[strong]] = True
    return good[lab]


def subpixel_edges(
    gray: np.ndarray,
    sigma: float = 1.0,
    low: float | None = None,
    high: float | None = None,
) -> EdgePoints:
    """Sub-pixel edge points of a luma image (Canny NMS + Devernay correction).

    Parameters
    ----------
    gray : ndarray, shape (H, W)
        Luma in [0, 1].
    sigma : float
        Standard deviation of the Gaussian pre-smoothing, pixels (0 disables it).
    low, high : float or None
        Hysteresis thresholds on the gradient norm, luma units per pixel.
        ``None`` chooses them from the image, see :func:`auto_thresholds`;
        a given ``low`` with ``high=None`` uses ``high = 2.5 low``, and vice
        versa ``low = high / 2.5``.

    Returns
    -------
    EdgePoints
        Points in row-major order of their pixels (deterministic).
    """
    gray = np.asarray(gray)
    if gray.ndim != 2:
        raise ValueError(f"gray must be a 2-D luma image, got shape {gray.shape}")
    if sigma < 0:
        raise ValueError("sigma must be >= 0")
    gx, gy, norm = _gradient(gray, sigma)
    if low is None and high is None:
        low, high = auto_thresholds(norm)
    elif low is None:
        low = high / _HIGH_LOW_RATIO
    elif high is None:
        high = _HIGH_LOW_RATIO * low
    if not 0 <= low <= high:
        raise ValueError(f"need 0 <= low <= high, got low={low}, high={high}")

    flat, offset, horizontal = _local_maxima(gx, gy, norm, low)
    strength = norm.ravel()[flat].astype(np.float64)
    keep = _hysteresis(flat, strength >= high, norm.shape)
    flat, offset, horizontal, strength = flat[keep], offset[keep], horizontal[keep], strength[keep]

    row, col = np.divmod(flat, norm.shape[1])
    xy = np.column_stack(
        (col + np.where(horizontal, offset, 0.0), row + np.where(horizontal, 0.0, offset))
    )
    g = np.column_stack((gx.ravel()[flat], gy.ravel()[flat])).astype(np.float64)
    normal = g / strength[:, None]
    return EdgePoints(
        xy=xy,
        normal=normal,
        strength=strength,
        pixel=np.column_stack((row, col)).astype(np.int64),
        low=float(low),
        high=float(high),
    )
