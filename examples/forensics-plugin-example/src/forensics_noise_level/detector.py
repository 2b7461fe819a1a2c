"""Noise level detector: Immerkaer's fast noise estimate, for the whole photo and per block.

A pasted region often carries noise of another level than its host. This
example reports the level and how much it varies between blocks, and
outlines the block that departs most; it states no p-value, so the fused
likelihood ratio does not rest on it.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import convolve

from forensics_core import Detector, DetectorResult, DetectorSpec, Status
from forensics_core.report import ReportSection

# Immerkaer's mask: the difference of two Laplacians, which cancels image
# structure up to second order and leaves the noise.
_MASK = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], dtype=np.float64)


def noise_sigma(luma: np.ndarray) -> float:
    """Noise standard deviation of ``luma``, in 8-bit grey levels.

    Parameters
    ----------
    luma : ndarray, shape (H, W)
        Grey levels in [0, 1]; H and W at least 3.

    Returns
    -------
    float
        sigma = sqrt(pi / 2) / (6 (W - 2)(H - 2)) * sum |I * N| (Immerkaer 1996, eq. 3).

    References
    ----------
    .. [1] J. Immerkaer, Fast noise variance estimation, Computer Vision and
       Image Understanding 64(2), 1996, pp. 300-302.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> round(noise_sigma(0.5 + rng.normal(0, 4 / 255, (256, 256))), 1)
    4.0
    """
    h, w = luma.shape
    response = np.abs(convolve(luma * 255.0, _MASK, mode="reflect"))[1:-1, 1:-1]
    return float(np.sqrt(np.pi / 2.0) * response.sum() / (6.0 * (w - 2) * (h - 2)))


class NoiseLevel(Detector):
    """The photo's noise level, per block, and the block that departs most."""

    spec = DetectorSpec(
        name="noise_level",
        version="0.2.0",
        description="Sensor noise level of the photo and its spread between blocks.",
        references=("J. Immerkaer, Fast noise variance estimation, CVIU 64(2), 1996.",),
        default_params={"block": 128},
        calibrated_on="score",
    )

    def analyze(self, evidence, params):
        luma = evidence.luma
        block = int(params["block"])
        if min(luma.shape) < 2 * block:
            return DetectorResult(Status.INCONCLUSIVE, f"The photo is smaller than two {block}-pixel blocks.")
        rows, cols = luma.shape[0] // block, luma.shape[1] // block
        levels = np.array([[noise_sigma(luma[r * block:(r + 1) * block, c * block:(c + 1) * block])
                            for c in range(cols)] for r in range(rows)])
        sigma = noise_sigma(luma)
        r, c = np.unravel_index(np.argmax(np.abs(levels - np.median(levels))), levels.shape)
        return DetectorResult(
            status=Status.OK,
            summary=f"Noise level {sigma:.2f} grey levels; blocks range {levels.min():.2f}-{levels.max():.2f}.",
            score=float(min(1.0, np.ptp(levels) / max(sigma, 1e-6) / 4)),
            details={"sigma": sigma, "block_sigma": levels, "block": block, "most_departing": [int(r), int(c)]},
            headline=f"Noise {sigma:.2f} grey levels; blocks from {levels.min():.2f} to {levels.max():.2f}.",
        )

    def report_section(self, finding, evidence):
        return ReportSection(
            title="Noise level",
            template="<p>Estimated noise: {{ sigma | round(2) }} grey levels (Immerkaer 1996), "
                     "measured in {{ block }}-pixel blocks.</p>",
            context={"sigma": finding.details["sigma"], "block": finding.details["block"]},
        )

    def localize(self, finding, shape):
        mask = np.zeros(shape, dtype=bool)
        r, c = finding.details["most_departing"]
        block = finding.details["block"]
        mask[r * block:(r + 1) * block, c * block:(c + 1) * block] = True
        return mask
