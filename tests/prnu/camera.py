"""Synthetic cameras for the prnu tests: each a fixed multiplicative sensor pattern, photos made through it.

Real PRNU is a gain of about 1 % per pixel; these cameras use 3 % so that
photos of 1.5 MP, small enough for a unit test, carry it clearly.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
from PIL import Image

SHAPE = (1024, 1536)


def pattern(seed: int, shape: tuple[int, int] = SHAPE) -> np.ndarray:
    """The camera's gain deviations, shape (H, W)."""
    return np.random.default_rng(seed).normal(0.0, 0.03, shape)


def scene(seed: int, shape: tuple[int, int] = SHAPE, flat: bool = False) -> np.ndarray:
    """A scene's radiance in 8-bit units, shape (H, W, 3): smooth for a flat field, with shapes otherwise."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0: shape[0], 0: shape[1]] / max(shape)
    base = 150 + 40 * np.sin(2 * np.pi * (xx * rng.uniform(0.3, 1) + yy * rng.uniform(0.3, 1)))
    if not flat:
        rows, cols = np.mgrid[0: shape[0], 0: shape[1]]
        for _ in range(12):
            (cy, cx), r = rng.uniform(0, 1, 2) * shape, rng.uniform(20, 90)
            inside = (rows - cy) ** 2 + (cols - cx) ** 2 < r * r
            base = np.where(inside, base * rng.uniform(0.6, 1.2), base)
    colour = np.array([1.0, 0.95, 0.85])
    return base[..., None] * colour


def shoot(radiance: np.ndarray, gain: np.ndarray, seed: int, quality: int = 95) -> bytes:
    """JPEG bytes of ``radiance`` taken through a sensor of ``gain`` with shot and read noise."""
    rng = np.random.default_rng(seed)
    signal = radiance * (1.0 + gain[..., None])
    noisy = signal + rng.normal(0.0, 1.0, signal.shape) * np.sqrt(signal / 40.0 + 1.0)
    buffer = io.BytesIO()
    Image.fromarray(np.clip(np.round(noisy), 0, 255).astype(np.uint8)).save(buffer, "JPEG", quality=quality)
    return buffer.getvalue()


def references(folder: Path, camera: int, count: int = 8) -> Path:
    """``count`` flat-field photos of camera ``camera`` written into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    gain = pattern(camera)
    for i in range(count):
        (folder / f"ref_{i:02d}.jpg").write_bytes(shoot(scene(1000 + i, flat=True), gain, 2000 + i))
    return folder


def photo(camera: int, seed: int) -> bytes:
    """A natural photo of camera ``camera``."""
    return shoot(scene(seed), pattern(camera), seed + 7)


def spliced(host_camera: int, donor_camera: int, seed: int, box: tuple[int, int, int, int]) -> bytes:
    """A photo of ``host_camera`` with ``box`` (y, x, height, width) from a photo of ``donor_camera``, saved at 95."""
    radiance = scene(seed)
    host = radiance * (1.0 + pattern(host_camera)[..., None])
    donor = radiance * (1.0 + pattern(donor_camera)[..., None])
    y, x, h, w = box
    host[y:y + h, x:x + w] = donor[y:y + h, x:x + w]
    rng = np.random.default_rng(seed + 7)
    noisy = host + rng.normal(0.0, 1.0, host.shape) * np.sqrt(host / 40.0 + 1.0)
    buffer = io.BytesIO()
    Image.fromarray(np.clip(np.round(noisy), 0, 255).astype(np.uint8)).save(buffer, "JPEG", quality=95)
    return buffer.getvalue()
