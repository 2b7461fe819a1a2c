"""Noise level detector: Immerkaer's fast noise estimate, for the whole photo and per block.

A pasted region often carries noise of another level than its host. This
example reports the level and how much it varies between blocks; it states no
p-value, so the verdict does not rest on it.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import convolve

from forensics_core import DetectorResult, DetectorSpec, Status, hookimpl
from forensics_core.report import ReportSection

NAME = "noise_level"
VERSION = "0.1.0"

# Immerkaer's mask: the difference of two Laplacians, which cancels image
# structure up to second order and leaves the noise.
_MASK = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], dtype=np.float64)


def noise_sigma(luma: np.ndarray) -> float:
    """Noise standard deviation of ``luma`` (shape (H, W), values in [0, 1]), in 8-bit grey levels.

    Immerkaer (1996), eq. 3: sigma = sqrt(pi / 2) / (6 (W - 2)(H - 2)) * sum |I * N|.
    """
    h, w = luma.shape
    response = np.abs(convolve(luma * 255.0, _MASK, mode="reflect"))[1:-1, 1:-1]
    return float(np.sqrt(np.pi / 2.0) * response.sum() / (6.0 * (w - 2) * (h - 2)))


@hookimpl
def forensics_register_detectors():
    return [
        DetectorSpec(
            name=NAME,
            version=VERSION,
            description="Sensor noise level of the photo and its spread between blocks.",
            references=("J. Immerkaer, Fast noise variance estimation, CVIU 64(2), 1996.",),
            default_params={"block": 128},
        )
    ]


@hookimpl
def forensics_analyze(detector, evidence, params):
    if detector != NAME:
        return None
    luma = evidence.luma
    block = int(params["block"])
    if min(luma.shape) < 2 * block:
        return DetectorResult(Status.INCONCLUSIVE, f"The photo is smaller than two {block}-pixel blocks.")
    rows, cols = luma.shape[0] // block, luma.shape[1] // block
    levels = np.array(
        [[noise_sigma(luma[r * block:(r + 1) * block, c * block:(c + 1) * block]) for c in range(cols)] for r in range(rows)]
    )
    sigma = noise_sigma(luma)
    return DetectorResult(
        status=Status.OK,
        summary=f"Noise level {sigma:.2f} grey levels; blocks range {levels.min():.2f}-{levels.max():.2f}.",
        details={"sigma": sigma, "block_sigma": levels, "block": block},
    )


@hookimpl
def forensics_report_section(finding, evidence):
    if finding.name != NAME:
        return None
    return ReportSection(
        title="Noise level",
        template="<p>Estimated noise: {{ sigma | round(2) }} grey levels (Immerkaer 1996).</p>",
        context={"sigma": finding.details.get("sigma", 0.0)},
    )
