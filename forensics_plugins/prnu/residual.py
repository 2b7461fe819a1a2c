"""The noise residual of a photo: what a wavelet denoiser takes away, where the sensor's PRNU lives.

The residual ``W = I - F(I)`` of Lukáš, Fridrich & Goljan (2006), eq. (2),
with the denoiser ``F`` of Mihcak, Kozintsev & Ramchandran (1999): four
levels of the 8-tap Daubechies wavelet (PyWavelets ``db4``), each detail
coefficient shrunk by a locally adaptive Wiener filter whose signal variance
is the smallest of the estimates over 3x3, 5x5, 7x7 and 9x9 windows. The part
the filter removes, ``c * s0^2 / (s^2 + s0^2)``, is kept directly in the
wavelet domain, and the approximation band is dropped (its content is scene,
not sensor).

References
----------
J. Lukáš, J. Fridrich, M. Goljan, "Digital camera identification from sensor
pattern noise", IEEE TIFS 1(2), 2006, pp. 205-214.
M. K. Mihcak, I. Kozintsev, K. Ramchandran, "Spatially adaptive statistical
modeling of wavelet image coefficients and its application to denoising",
ICASSP 1999, pp. 3253-3256.
M. Chen, J. Fridrich, M. Goljan, J. Lukáš, "Determining image origin and
integrity using sensor noise", IEEE TIFS 3(1), 2008, pp. 74-90.
"""

from __future__ import annotations

import numpy as np
import pywt
import scipy.fft
from scipy.ndimage import uniform_filter

WAVELET = "db4"
LEVELS = 4
WINDOWS = (3, 5, 7, 9)
# Pixels at or above this level (8-bit) clipped: their residual holds no PRNU
# (Chen et al. 2008, sec. III-A).
SATURATED = 250.0
# Luma weights of ITU-R BT.601, as the reference implementation combines the
# colour channels' residuals.
BT601 = np.array([0.299, 0.587, 0.114])


def wiener_residual(coefficients: np.ndarray, sigma0: float, *, wrap: bool = False) -> np.ndarray:
    """The part of ``coefficients`` a locally adaptive Wiener filter removes as noise of variance ``sigma0**2``.

    Parameters
    ----------
    coefficients : ndarray, shape (M, N)
        One band (a wavelet detail band, or the magnitudes of a spectrum).
    sigma0 : float
        Standard deviation of the noise, in the band's units.
    wrap : bool
        Windows wrap around the edges (a periodic spectrum) instead of mirroring.

    Returns
    -------
    ndarray, shape (M, N)
        ``c * sigma0**2 / (s**2 + sigma0**2)`` with ``s**2`` the smallest of the
        local signal-variance estimates ``max(0, mean_w(c**2) - sigma0**2)``
        (Mihcak et al. 1999, eq. 9; Lukáš et al. 2006, appendix A).
    """
    mode = "wrap" if wrap else "mirror"
    squared = coefficients * coefficients
    noise = sigma0 * sigma0
    signal = np.full(coefficients.shape, np.inf)
    for w in WINDOWS:
        np.minimum(signal, np.maximum(uniform_filter(squared, w, mode=mode) - noise, 0.0), out=signal)
    return coefficients * (noise / (signal + noise))


def channel_residual(channel: np.ndarray, sigma0: float = 3.0) -> np.ndarray:
    """The noise residual of one channel (Lukáš et al. 2006, eq. 2 and appendix A).

    Parameters
    ----------
    channel : ndarray, shape (H, W)
        Intensities in 8-bit units (0-255), float.
    sigma0 : float
        The denoiser's noise standard deviation, 8-bit units (3, as Lukáš et al.).

    Returns
    -------
    ndarray, shape (H, W), float32
    """
    height, width = channel.shape
    step = 2 ** LEVELS
    padded = np.pad(channel, ((0, -height % step), (0, -width % step)), mode="symmetric")
    coeffs = pywt.wavedec2(padded, WAVELET, mode="periodization", level=LEVELS)
    kept = [np.zeros_like(coeffs[0])]
    for bands in coeffs[1:]:
        kept.append(tuple(wiener_residual(band, sigma0) for band in bands))
    return pywt.waverec2(kept, WAVELET, mode="periodization")[:height, :width].astype(np.float32)


def zero_mean(residual: np.ndarray) -> np.ndarray:
    """``residual`` with the mean of every row and every column removed on each 2x2 colour-filter lattice.

    Rows and columns of a sensor's readout and the demosaicing share patterns
    across cameras of one model (non-unique artefacts); removing each row's
    and column's mean on each of the four lattices of the colour filter
    removes them (Chen et al. 2008, sec. III-B, "zero-mean").

    Parameters
    ----------
    residual : ndarray, shape (H, W)

    Returns
    -------
    ndarray, shape (H, W), float32

    Examples
    --------
    A pattern shared by every row (a column pattern of the readout) is removed:

    >>> import numpy as np
    >>> columns = np.tile(np.arange(8.0), (8, 1))
    >>> float(abs(zero_mean(columns)).max())
    0.0
    """
    out = residual.astype(np.float32, copy=True)
    for dy in (0, 1):
        for dx in (0, 1):
            lattice = out[dy::2, dx::2]
            lattice -= lattice.mean(axis=0, keepdims=True)
            lattice -= lattice.mean(axis=1, keepdims=True)
    return out


def wiener_dft(residual: np.ndarray) -> np.ndarray:
    """``residual`` with the peaks of its spectrum flattened: periodic patterns shared by a camera model removed.

    The magnitude of the 2-D DFT is passed through :func:`wiener_residual`
    with the residual's own standard deviation as the noise level, and the
    spectrum rescaled to it, phases kept (Chen et al. 2008, sec. III-B,
    "Wiener filtering in the Fourier domain"). JPEG's 8x8 blocking and the
    colour interpolation leave such peaks in every camera of a model.

    Parameters
    ----------
    residual : ndarray, shape (H, W)

    Returns
    -------
    ndarray, shape (H, W), float32
    """
    spectrum = scipy.fft.rfft2(residual.astype(np.float32))
    magnitude = np.abs(spectrum) / np.float32(np.sqrt(residual.size))
    flattened = wiener_residual(magnitude, float(residual.std()), wrap=True)
    scale = np.divide(flattened, magnitude, out=np.zeros_like(magnitude), where=magnitude > 0)
    return scipy.fft.irfft2(spectrum * scale, s=residual.shape).astype(np.float32)


def eight_bit(pixels: np.ndarray) -> np.ndarray:
    """``pixels`` in 8-bit units: uint8 as is, uint16 shifted, other types clipped to [0, 255]."""
    if pixels.dtype == np.uint8:
        return pixels
    if pixels.dtype == np.uint16:
        return (pixels >> 8).astype(np.uint8)
    return np.clip(pixels, 0, 255).astype(np.uint8)


def noise_residual(pixels: np.ndarray, sigma0: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """Each colour channel's residual and intensity, with clipped pixels zeroed.

    Parameters
    ----------
    pixels : ndarray, shape (H, W) or (H, W, C), uint8
    sigma0 : float
        As :func:`channel_residual`.

    Returns
    -------
    residuals : ndarray, shape (C, H, W), float32
    intensities : ndarray, shape (C, H, W), float32
        The channels in 8-bit units, 0 where clipped.
    """
    image = pixels[..., :3] if pixels.ndim == 3 else pixels[..., None]
    channels = np.moveaxis(image, -1, 0).astype(np.float32)
    residuals = np.stack([channel_residual(c, sigma0) for c in channels])
    clipped = channels >= SATURATED
    residuals[clipped] = 0.0
    channels[clipped] = 0.0
    return residuals, channels


def luma(stack: np.ndarray) -> np.ndarray:
    """BT.601 luma of a ``(3, H, W)`` stack, or its only channel of a ``(1, H, W)`` one; shape (H, W)."""
    if stack.shape[0] == 1:
        return stack[0]
    return np.tensordot(BT601.astype(np.float32), stack, axes=1)


def test_residual(pixels: np.ndarray, sigma0: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """The residual a photo is tested with, and its luma (Chen et al. 2008, sec. III-C).

    Returns
    -------
    residual : ndarray, shape (H, W), float32
        Zero-meaned per channel, combined to luma, Wiener-filtered in the DFT.
    intensity : ndarray, shape (H, W), float32
        Luma in 8-bit units, 0 where a channel clipped.
    """
    residuals, channels = noise_residual(pixels, sigma0)
    combined = luma(np.stack([zero_mean(r) for r in residuals]))
    image = pixels[..., :3] if pixels.ndim == 3 else pixels[..., None]
    intensity = luma(channels)
    intensity[(image >= SATURATED).any(axis=-1)] = 0.0
    return wiener_dft(combined), intensity
