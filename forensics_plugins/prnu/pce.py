"""Whether a photo carries a fingerprint: the peak-to-correlation energy of their cross-correlation.

The photo's residual weighted by its intensity, ``I W`` (:mod:`.residual`),
is cross-correlated with the fingerprint ``K`` over every circular shift
(Goljan & Fridrich 2008, eq. 4). Where the photo came from the camera, the
correlation peaks at the shift that aligns them; elsewhere it is noise. The
PCE is the squared peak over the mean square of the correlation away from
it (an 11 x 11 neighbourhood left out), with the peak's sign:
``PCE = sign(c_peak) c_peak^2 / mean_{s not near peak}(c_s^2)`` (eq. 5).
Without the fingerprint, the correlation at one fixed shift is a zero-mean
Gaussian whose variance the energy estimates, so the PCE there follows a
chi-squared law with one degree of freedom and ``z = sign(PCE) sqrt(|PCE|)``
is standard normal: :func:`z_score` is the score the likelihood ratio is
calibrated on.

References
----------
M. Goljan, J. Fridrich, "Camera identification from cropped and scaled
images", Proc. SPIE 6819, Security, Forensics, Steganography, and
Watermarking of Multimedia Contents X, 2008.
M. Chen, J. Fridrich, M. Goljan, J. Lukáš, "Determining image origin and
integrity using sensor noise", IEEE TIFS 3(1), 2008, pp. 74-90.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.fft

# The neighbourhood of the peak left out of the correlation energy, pixels
# (Goljan & Fridrich 2008): interpolation spreads the peak over a few pixels.
EXCLUDED = 11


@dataclass(frozen=True)
class Peak:
    """The result of one alignment test.

    Attributes
    ----------
    pce : float
        Signed peak-to-correlation energy at the peak.
    shift : tuple of int
        (dy, dx), pixels: where the photo's top-left corner lies in the
        fingerprint's frame.
    searched : int
        Shifts searched for the peak (1 when the alignment was fixed).
    rotation : int
        Degrees (0, 90, 180, 270) the photo's grid was turned to match the fingerprint's.
    scale : float
        Factor by which the fingerprint was resampled to the photo's scale.
    """

    pce: float
    shift: tuple[int, int]
    searched: int
    rotation: int = 0
    scale: float = 1.0

    @property
    def z(self) -> float:
        """``sign(PCE) sqrt(|PCE|)``: a standard normal value at a fixed alignment without the fingerprint."""
        return math.copysign(math.sqrt(abs(self.pce)), self.pce)


def fingerprint_spectrum(fingerprint: np.ndarray) -> np.ndarray:
    """The real 2-D DFT of the zero-mean fingerprint, for several :func:`cross_correlation` calls."""
    return scipy.fft.rfft2(fingerprint - fingerprint.mean())


def cross_correlation(signal: np.ndarray, fingerprint: np.ndarray, spectrum: np.ndarray | None = None) -> np.ndarray:
    """Circular cross-correlation ``c[s] = sum_x K(x + s) X(x)`` of ``X`` (zero-padded to ``K``'s size) with ``K``.

    Parameters
    ----------
    signal : ndarray, shape (h, w)
        ``I W`` of the photo, ``h <= H`` and ``w <= W``.
    fingerprint : ndarray, shape (H, W)
    spectrum : ndarray, optional
        :func:`fingerprint_spectrum` of ``fingerprint``, when already computed.

    Returns
    -------
    ndarray, shape (H, W), float32
        Indexed by the shift (dy, dx) of the photo's origin in the fingerprint's frame.
    """
    shape = fingerprint.shape
    padded = np.zeros(shape, np.float32)
    padded[: signal.shape[0], : signal.shape[1]] = signal - signal.mean()
    if spectrum is None:
        spectrum = fingerprint_spectrum(fingerprint)
    return scipy.fft.irfft2(spectrum * np.conj(scipy.fft.rfft2(padded)), s=shape).astype(np.float32)


def peak_energy(correlation: np.ndarray, allowed: tuple[int, int]) -> tuple[float, tuple[int, int], int]:
    """The signed PCE at the highest correlation among shifts ``[0, allowed[0]) x [0, allowed[1])``.

    Parameters
    ----------
    correlation : ndarray, shape (H, W)
        From :func:`cross_correlation`.
    allowed : tuple of int
        Shifts searched in each axis; (1, 1) tests the fixed alignment (0, 0).

    Returns
    -------
    pce : float
    shift : tuple of int
    searched : int

    Examples
    --------
    A fingerprint correlated with itself peaks at the zero shift:

    >>> import numpy as np
    >>> k = np.random.default_rng(0).normal(size=(64, 64)).astype(np.float32)
    >>> pce, shift, searched = peak_energy(cross_correlation(k, k), (1, 1))
    >>> shift, searched, pce > 1000
    ((0, 0), 1, True)
    """
    window = correlation[: allowed[0], : allowed[1]]
    dy, dx = np.unravel_index(int(np.argmax(window)), window.shape)
    peak = float(correlation[dy, dx])
    height, width = correlation.shape
    half = EXCLUDED // 2
    keep = np.ones(correlation.shape, bool)
    rows = np.arange(dy - half, dy + half + 1) % height
    cols = np.arange(dx - half, dx + half + 1) % width
    keep[np.ix_(rows, cols)] = False
    energy = float(np.mean(np.square(correlation[keep], dtype=np.float64)))
    pce = math.copysign(peak * peak / energy, peak) if energy > 0 else 0.0
    return pce, (int(dy), int(dx)), int(window.size)
