"""Synthetic cases for the dq detector: photos saved twice as JPEG, some with a piece pasted between the saves.

The scene is smooth shading, shapes and sensor-like grain (the coefficients
need texture to carry a quantisation). Authentic: saved at quality ``q1``,
decoded, saved at ``q2`` (or saved once, on which the detector must decline).
Spliced: between the two saves a piece of another scene, never compressed or
compressed on a shifted grid, replaces an ellipse of the photo.
"""

from __future__ import annotations

import io
from collections.abc import Iterator

import numpy as np
from PIL import Image

from forensics_core import SyntheticCase, grey_shapes, paste_ellipse
from forensics_core import grey_jpeg as encode

DEFAULT_SIZE = (1024, 768)


def scene(rng: np.random.Generator, size: tuple[int, int]) -> np.ndarray:
    """A grey scene with sensor-like grain, float in [0, 255], shape (height, width)."""
    img = grey_shapes(rng, size)
    img += rng.normal(0, rng.uniform(2.5, 5.0), img.shape).astype(np.float32)
    return np.clip(img, 8, 247)


def decode(data: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(data)) as img:
        return np.asarray(img.convert("L"), dtype=np.float32)


def paste(host: np.ndarray, rng: np.random.Generator, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """The host with an ellipse from another scene, and the ellipse's mask."""
    h, w = host.shape
    donor = scene(rng, (w, h))
    if kind == "shifted_jpeg":
        dy, dx = (int(v) for v in rng.integers(1, 8, 2))
        shifted = decode(encode(donor[dy:, dx:], int(rng.choice([60, 75]))))
        donor[dy:, dx:] = shifted
    return paste_ellipse(host, donor, rng)


def synthetic_cases(seed: int, count: int, size: tuple[int, int] = DEFAULT_SIZE) -> Iterator[SyntheticCase]:
    """About ``count`` authentic and ``count`` spliced cases, deterministic in ``seed``."""
    rng = np.random.default_rng([seed, 5])
    for i in range(count):
        q1, q2 = int(rng.choice([65, 75, 85])), int(rng.choice([90, 95]))
        host = scene(rng, size)
        once = decode(encode(host, q1))
        single = i % 4 == 3
        tag = {"q1": str(q1), "jpeg_quality": str(q2), "size": f"{size[0]}x{size[1]}"}
        yield SyntheticCase(f"dq-authentic-{i:03d}", encode(host if single else once, q2), ".jpg", False, None,
                            {"kind": "none", "saves": "1" if single else "2", **tag})
        kind = ("raw", "shifted_jpeg")[i % 2]
        spliced, mask = paste(once, rng, kind)
        yield SyntheticCase(f"dq-spliced-{i:03d}", encode(spliced, q2), ".jpg", True, mask,
                            {"kind": f"dq_{kind}", "saves": "2", **tag})
