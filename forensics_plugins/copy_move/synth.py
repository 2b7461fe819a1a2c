"""Synthetic copy-moves and repetitive authentic scenes for ``forensics validate`` and the tests.

Each scene is a smooth random field with a row of identical "windows" (the
same drawn structure repeated, as on a facade) and sensor noise added after
drawing, so the repeated structure carries independent grain: the situation
in which keypoints match and a copy-move detector must not convict. The
spliced version copies a square of the noisy photo elsewhere (shifted,
rotated or scaled) before the file is saved, as an editor's clone tool does.
"""

from __future__ import annotations

from collections.abc import Iterator

import cv2
import numpy as np

from forensics_core import SyntheticCase, grey_jpeg as encode

DEFAULT_SIZE = (600, 800)
_TRANSFORMS = ("translation", "rotation", "scale")


def scene(rng: np.random.Generator, size: tuple[int, int]) -> np.ndarray:
    """A grey scene with repeated structure and independent noise, float 0-255, shape ``size``."""
    h, w = size
    field = cv2.resize(rng.normal(0.0, 1.0, (h // 32 + 2, w // 32 + 2)).astype(np.float32), (w, h),
                       interpolation=cv2.INTER_CUBIC)
    texture = cv2.GaussianBlur(rng.normal(0.0, 1.0, (h, w)).astype(np.float32), (0, 0), 1.5)
    img = 120.0 + 35.0 * field + 12.0 * texture
    for _ in range(200):
        centre = (int(rng.integers(0, w)), int(rng.integers(0, h)))
        axes = (int(rng.integers(3, 24)), int(rng.integers(3, 24)))
        cv2.ellipse(img, centre, axes, float(rng.uniform(0, 180)), 0, 360, float(rng.uniform(20, 235)), -1)
    # Manufactured repetition: one design, each copy with its own fine
    # texture (dirt, reflections), as real windows of a facade are.
    cell = rng.normal(0.0, 1.0, (48, 32)).astype(np.float32)
    window = 70.0 + 40.0 * cv2.GaussianBlur(cell, (0, 0), 3.0)
    top = int(rng.integers(h // 8, h // 3))
    for x in range(w // 16, w - 48, 64):
        own = cv2.GaussianBlur(rng.normal(0.0, 1.0, (48, 32)).astype(np.float32), (0, 0), 1.0)
        img[top: top + 48, x: x + 32] = window + 8.0 * own
    img = cv2.GaussianBlur(img.astype(np.float32), (0, 0), 0.7) + rng.normal(0.0, 3.0, img.shape)
    return np.clip(img, 0, 255)


def clone(img: np.ndarray, rng: np.random.Generator, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """``img`` with a square copied elsewhere under ``kind``; the image and the mask of the copy."""
    h, w = img.shape
    side = int(rng.integers(min(h, w) // 4, min(h, w) // 3))
    while True:
        sy, sx = int(rng.integers(0, h - side)), int(rng.integers(0, w - side))
        ty, tx = int(rng.integers(0, h - side)), int(rng.integers(0, w - side))
        if abs(sx - tx) > side or abs(sy - ty) > side:
            break
    angle = float(rng.uniform(10, 40)) if kind == "rotation" else 0.0
    factor = float(rng.uniform(0.8, 1.25)) if kind == "scale" else 1.0
    centre_src = (sx + side / 2, sy + side / 2)
    m = cv2.getRotationMatrix2D(centre_src, angle, factor)
    m[:, 2] += (tx - sx, ty - sy)
    moved = cv2.warpAffine(img.astype(np.float32), m, (w, h), flags=cv2.INTER_LINEAR)
    disc = np.zeros((h, w), np.uint8)
    cv2.circle(disc, (tx + side // 2, ty + side // 2), side // 2, 1, -1)
    mask = disc.astype(bool)
    out = img.copy()
    out[mask] = moved[mask]
    return out, mask


def synthetic_cases(seed: int, count: int, size: tuple[int, int] = DEFAULT_SIZE) -> Iterator[SyntheticCase]:
    """``count`` authentic and ``count`` cloned cases; the transform cycles through shift, rotation and scale."""
    for i in range(count):
        case_seed = seed * 100003 + i
        rng = np.random.default_rng(case_seed)
        img = scene(rng, size)
        kind = _TRANSFORMS[i % len(_TRANSFORMS)]
        quality = (95, 90, 85)[i % 3]
        cloned, mask = clone(img, rng, kind)
        for spliced, pixels in ((False, img), (True, cloned)):
            yield SyntheticCase(
                name=f"copy_move-{'spliced' if spliced else 'authentic'}-{case_seed}",
                data=encode(pixels, quality), suffix=".jpg", spliced=spliced, mask=mask if spliced else None,
                conditions={"kind": f"copy_{kind}" if spliced else "none", "jpeg_quality": str(quality),
                            "scene": f"copy_move-{case_seed}"})
