"""Finding the photo's place in the fingerprint's frame: orientation, crop and scale.

A photo of the full frame is tested at the one alignment its size implies
(and turned by 180 degrees, or by 90 and 270 when its sides are swapped). A
smaller photo may be a crop, or the full frame scaled down: the crop is
searched over every shift at which it fits (Goljan & Fridrich 2008), the
scaling at the one factor that maps the frame onto the photo when their
aspects agree. The more alignments searched, the higher the largest chance
peak; :func:`single_test_z` states the best peak as the standard-normal
value of one test with the same tail probability (Šidák's correction for the
alignments searched, as if independent), the score the likelihood ratio is
calibrated on.

References
----------
M. Goljan, J. Fridrich, "Camera identification from cropped and scaled
images", Proc. SPIE 6819, 2008.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.ndimage import zoom
from scipy.stats import norm

from .pce import Peak, cross_correlation, fingerprint_spectrum, peak_energy

# Aspect ratios within this relative difference count as one frame scaled.
ASPECT_TOLERANCE = 0.01


def _turned(array: np.ndarray, rotation: int) -> np.ndarray:
    return np.rot90(array, k=rotation // 90)


def candidates(photo: tuple[int, int], frame: tuple[int, int]) -> list[tuple[int, float]]:
    """(rotation, scale) pairs worth testing for a photo of size ``photo`` in a fingerprint of size ``frame``.

    Rotations turn the photo's residual counter-clockwise, in degrees; a
    scale below 1 resamples the fingerprint down to the photo's scale.
    Empty when the photo fits the frame in no orientation.

    Examples
    --------
    >>> candidates((2000, 3008), (2000, 3008))
    [(0, 1.0), (180, 1.0)]
    >>> candidates((1000, 1504), (2000, 3008))[:2]
    [(0, 1.0), (0, 0.5)]
    """
    out: list[tuple[int, float]] = []
    for rotation in (0, 90, 180, 270):
        h, w = photo if rotation in (0, 180) else photo[::-1]
        if h > frame[0] or w > frame[1]:
            continue
        out.append((rotation, 1.0))
        if (h, w) != frame and abs(h / w - frame[0] / frame[1]) <= ASPECT_TOLERANCE * frame[0] / frame[1]:
            out.append((rotation, h / frame[0]))
    return out


def best_alignment(signal: np.ndarray, fingerprint: np.ndarray) -> Peak | None:
    """The highest PCE over the alignments of :func:`candidates`; None when the photo fits the frame nowhere.

    Parameters
    ----------
    signal : ndarray, shape (h, w)
        ``I W`` of the photo, in its stored orientation.
    fingerprint : ndarray, shape (H, W)

    Returns
    -------
    Peak or None
        ``searched`` counts every alignment tried, over all candidates.
    """
    best: Peak | None = None
    searched = 0
    spectrum = None
    for rotation, scale in candidates(signal.shape, fingerprint.shape):
        turned = _turned(signal, rotation)
        if scale != 1.0:
            k = zoom(fingerprint, (turned.shape[0] / fingerprint.shape[0], turned.shape[1] / fingerprint.shape[1]),
                     order=1)
            allowed = (1, 1)
            correlation = cross_correlation(turned, k)
        else:
            if spectrum is None:
                spectrum = fingerprint_spectrum(fingerprint)
            allowed = (fingerprint.shape[0] - turned.shape[0] + 1, fingerprint.shape[1] - turned.shape[1] + 1)
            correlation = cross_correlation(turned, fingerprint, spectrum)
        pce, shift, count = peak_energy(correlation, allowed)
        searched += count
        if best is None or pce > best.pce:
            best = Peak(pce, shift, 0, rotation, scale)
    if best is None:
        return None
    return Peak(best.pce, best.shift, searched, best.rotation, best.scale)


def single_test_z(peak: Peak) -> float:
    """The best peak as one test's standard-normal value (Šidák): ``Phi^-1(1 - p)``, ``p = 1 - (1 - Q(z))^N``.

    Parameters
    ----------
    peak : Peak
        Its ``z`` is the largest of ``N = peak.searched`` alignments' values.

    Returns
    -------
    float
        Equal to ``peak.z`` for one alignment; lower the more were searched.
        Without the fingerprint, the largest of N independent standard
        normals maps to a standard normal again (at least about -7).
    """
    n = max(peak.searched, 1)
    if n == 1:
        return peak.z
    log_tail = norm.logsf(peak.z)
    if log_tail + math.log(n) < -20.0:
        # p = N Q(z) to double precision; beyond exp(-745) the inverse is asymptotic.
        log_p = log_tail + math.log(n)
        return float(norm.isf(math.exp(log_p))) if log_p > -700.0 else math.sqrt(-2.0 * log_p)
    p = -math.expm1(n * math.log1p(-math.exp(log_tail)))
    # A peak far below what N alignments give by chance: as low as one test can state.
    return float(norm.isf(min(p, 1.0 - 1e-12)))


def aligned(arrays: Sequence[np.ndarray], peak: Peak,
            fingerprint: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """The photo's ``arrays`` (same shape) turned as ``peak`` says, and the part of the fingerprint they lie on.

    The fingerprint is resampled once for all of them when the photo was scaled.
    """
    turned = [_turned(array, peak.rotation) for array in arrays]
    h, w = turned[0].shape[:2]
    if peak.scale != 1.0:
        return turned, zoom(fingerprint, (h / fingerprint.shape[0], w / fingerprint.shape[1]), order=1)
    dy, dx = peak.shift
    return turned, fingerprint[dy: dy + h, dx: dx + w]
