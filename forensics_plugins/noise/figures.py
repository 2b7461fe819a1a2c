"""The noise figure: the photo tinted by each area's noise against like content, with the listed windows.

Drawn from the photo and the block z-scores the finding carries
(:func:`.detector.encode_z`); the photo is reduced first, and the z-scores are
averaged over 4 x 4 blocks so that the map shows regions, not single blocks.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import cv2
import numpy as np
from PIL import Image, ImageDraw

from forensics_core.report import figure_png

MAX_SIDE = 1200
NOISIER = np.array([230, 40, 40], np.float32)
SMOOTHER = np.array([40, 90, 230], np.float32)
WINDOW = (255, 210, 0)
BEST = (255, 255, 255)
_SMOOTH_BLOCKS = 4
_FULL_TINT_Z = 2.0


def _fit(a: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """``a`` cut or zero-padded to ``size`` (width, height)."""
    out = np.zeros((size[1], size[0], *a.shape[2:]), a.dtype)
    h, w = min(size[1], a.shape[0]), min(size[0], a.shape[1])
    out[:h, :w] = a[:h, :w]
    return out


def z_map_png(luma: np.ndarray, z: np.ndarray, used: np.ndarray, details: Mapping[str, Any]) -> bytes:
    """PNG of the dimmed photo tinted red where blocks are noisier than like content, blue where smoother.

    Parameters
    ----------
    luma : ndarray, shape (H, W)
        In [0, 1].
    z, used : ndarray, shape (h, w)
        Block z-scores and the blocks used (:func:`.detector.decode_z`).
    details : mapping
        The finding's details (its ``windows`` are outlined in yellow, its
        ``best`` window in white).
    """
    h, w = luma.shape
    k = min(1.0, MAX_SIDE / max(h, w))
    size = (max(1, round(w * k)), max(1, round(h * k)))
    grey = np.clip(np.asarray(luma, dtype=np.float32), 0, 1) * 170 + 40
    grey = cv2.resize(grey, size, interpolation=cv2.INTER_AREA) if k < 1 else grey
    box = (_SMOOTH_BLOCKS, _SMOOTH_BLOCKS)
    n = cv2.blur(used.astype(np.float32), box, borderType=cv2.BORDER_CONSTANT)
    mean_z = np.where(n > 0, cv2.blur(z.astype(np.float32), box, borderType=cv2.BORDER_CONSTANT) / np.maximum(n, 1e-6),
                      0.0)
    strength = np.clip(np.abs(mean_z) / _FULL_TINT_Z, 0, 1) * (n > 0.5)
    tint = np.where((mean_z > 0)[..., None], NOISIER, SMOOTHER).astype(np.float32)
    # Straight from blocks to the figure's size: the blocks cover the photo but for its last H % 8 rows and
    # W % 8 columns, under a pixel once reduced.
    covered = (max(1, round(8 * z.shape[1] * k)), max(1, round(8 * z.shape[0] * k)))
    tint = _fit(cv2.resize(tint, covered, interpolation=cv2.INTER_NEAREST), size)
    weight = 0.6 * _fit(cv2.resize(strength.astype(np.float32), covered, interpolation=cv2.INTER_LINEAR), size)
    weight = weight[..., None]
    rgb = grey[..., None] * (1 - weight) + tint * weight
    img = Image.fromarray(np.clip(rgb, 0, 255).astype(np.uint8))
    draw = ImageDraw.Draw(img)
    for win, colour in [(x, WINDOW) for x in details.get("windows") or []] + [(details.get("best"), BEST)]:
        if win:
            x0, y0, side = 8 * win["col"] * k, 8 * win["row"] * k, 8 * win["size"] * k
            draw.rectangle([x0, y0, x0 + side, y0 + side], outline=colour, width=2)
    return figure_png(img)
