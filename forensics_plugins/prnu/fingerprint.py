"""The camera's fingerprint: the maximum-likelihood estimate of its PRNU from reference photos.

``K = sum_k W_k I_k / sum_k I_k^2`` per colour channel (Chen, Fridrich,
Goljan & Lukáš 2008, eq. 7), from each reference's residual ``W_k`` and
intensity ``I_k`` (:mod:`.residual`), then zero-meaned and combined to luma,
and Wiener-filtered in the DFT so that what every camera of the model shares
is gone (sec. III-B). Flat, bright, unclipped references (sky, a wall, a
sheet of paper out of focus) give the best estimate; twenty to fifty are
usual, ten already identify a camera.

References
----------
M. Chen, J. Fridrich, M. Goljan, J. Lukáš, "Determining image origin and
integrity using sensor noise", IEEE TIFS 3(1), 2008, pp. 74-90.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from .residual import luma, noise_residual, wiener_dft, zero_mean


@dataclass(frozen=True)
class Fingerprint:
    """An estimated PRNU fingerprint.

    Attributes
    ----------
    k : ndarray, shape (H, W), float32
        The fingerprint, luma, zero-meaned and Wiener-filtered (dimensionless:
        the relative gain of each pixel).
    count : int
        Reference photos it was estimated from.
    """

    k: np.ndarray
    count: int

    @property
    def shape(self) -> tuple[int, int]:
        return self.k.shape  # type: ignore[return-value]


def estimate(references: Iterable[np.ndarray], sigma0: float = 3.0) -> Fingerprint:
    """The fingerprint of the camera that took ``references`` (Chen et al. 2008, eq. 7 and sec. III-B).

    Parameters
    ----------
    references : iterable of ndarray, each shape (H, W, 3) or (H, W), uint8
        Photos of one camera, all of one size and orientation.
    sigma0 : float
        The denoiser's noise level (:func:`.residual.channel_residual`).

    Returns
    -------
    Fingerprint

    Raises
    ------
    ValueError
        For no references, or references of different sizes.
    """
    numerator = denominator = None
    count = 0
    for pixels in references:
        residuals, channels = noise_residual(pixels, sigma0)
        if numerator is None:
            numerator = np.zeros(residuals.shape, np.float64)
            denominator = np.zeros(residuals.shape, np.float64)
        elif residuals.shape != numerator.shape:
            raise ValueError(f"reference photos differ in size: {residuals.shape[1:]} and {numerator.shape[1:]}")
        numerator += residuals * channels
        denominator += channels * channels
        count += 1
    if numerator is None:
        raise ValueError("no reference photos")
    k = np.divide(numerator, denominator, out=np.zeros_like(numerator), where=denominator > 0).astype(np.float32)
    return Fingerprint(wiener_dft(luma(np.stack([zero_mean(c) for c in k]))), count)
