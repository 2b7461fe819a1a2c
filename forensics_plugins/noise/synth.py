"""Synthetic cases for the noise detector: photos with a piece whose grain differs from the rest.

The scene is smooth shading and shapes, blurred, then given sensor-like
Gaussian grain of one standard deviation ``sigma`` throughout (the detector
compares fine-grain energy, so the content itself carries none). Authentic:
such a scene saved once as JPEG. Spliced: before the save, an ellipse of the
photo is replaced by another scene whose grain differs: ``noisier`` (grain
2.5 to 3.5 times the host's) or ``smoother`` (rendered at half size and
enlarged twice, which smooths its grain away).
"""

from __future__ import annotations

from collections.abc import Iterator

import cv2
import numpy as np

from forensics_core import SyntheticCase, grey_shapes, paste_ellipse
from forensics_core import grey_jpeg as encode

DEFAULT_SIZE = (1024, 768)
KINDS = ("noisier", "smoother")


def scene(rng: np.random.Generator, size: tuple[int, int], sigma: float) -> np.ndarray:
    """A grey scene with grain of standard deviation ``sigma`` (grey levels), float in [0, 255], shape (h, w)."""
    img = grey_shapes(rng, size)
    img += rng.normal(0, sigma, img.shape).astype(np.float32)
    return np.clip(img, 8, 247)


def paste(host: np.ndarray, rng: np.random.Generator, kind: str, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """The host (grain ``sigma``) with an ellipse from another scene of other grain, and the ellipse's mask.

    ``kind`` is ``"noisier"`` (the donor's grain 2.5 to 3.5 times ``sigma``)
    or ``"smoother"`` (the donor, grain ``sigma``, rendered at half size and
    enlarged twice with bilinear interpolation, and given no grain after).
    """
    h, w = host.shape
    if kind == "noisier":
        donor = scene(rng, (w, h), sigma * rng.uniform(2.5, 3.5))
    elif kind == "smoother":
        small = scene(rng, ((w + 1) // 2, (h + 1) // 2), sigma)
        donor = cv2.resize(small, (2 * small.shape[1], 2 * small.shape[0]), interpolation=cv2.INTER_LINEAR)[:h, :w]
    else:
        raise ValueError(f"unknown kind {kind!r}; expected one of {KINDS}")
    return paste_ellipse(host, donor, rng)


def synthetic_cases(seed: int, count: int, size: tuple[int, int] = DEFAULT_SIZE) -> Iterator[SyntheticCase]:
    """``count`` authentic and ``count`` spliced cases, deterministic in ``seed``."""
    rng = np.random.default_rng([seed, 8])
    for i in range(count):
        sigma, quality = float(rng.uniform(2.0, 4.0)), int(rng.choice([90, 95]))
        host = scene(rng, size, sigma)
        tag = {"sigma": f"{sigma:.2f}", "jpeg_quality": str(quality), "size": f"{size[0]}x{size[1]}"}
        yield SyntheticCase(f"noise-authentic-{i:03d}", encode(host, quality), ".jpg", False, None,
                            {"kind": "none", **tag})
        kind = KINDS[i % 2]
        spliced, mask = paste(host, rng, kind, sigma)
        yield SyntheticCase(f"noise-spliced-{i:03d}", encode(spliced, quality), ".jpg", True, mask,
                            {"kind": f"noise_{kind}", **tag})
