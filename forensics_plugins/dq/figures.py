"""The dq figure: the photo with each block's vote and the windows that lack the earlier quantisation.

Drawn from the photo and the block votes the finding carries
(:func:`.votes.encode_votes`); the photo is reduced first.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import cv2
import numpy as np
from PIL import Image, ImageDraw

from forensics_core.report import figure_png

MAX_SIDE = 1200
SINGLE = np.array([230, 40, 40], np.float32)
DOUBLE = np.array([40, 170, 90], np.float32)
WINDOW = (255, 210, 0)


def votes_png(luma: np.ndarray, informative: np.ndarray, single: np.ndarray, details: Mapping[str, Any]) -> bytes:
    """PNG of the dimmed photo tinted red where a block votes single compression, green where double.

    Parameters
    ----------
    luma : ndarray, shape (H, W)
        In [0, 1].
    informative, single : ndarray of bool, shape (h, w)
        Block votes (:func:`.votes.decode_votes`).
    details : mapping
        The finding's details (its ``windows`` are outlined).
    """
    h, w = luma.shape
    k = min(1.0, MAX_SIDE / max(h, w))
    size = (max(1, round(w * k)), max(1, round(h * k)))
    grey = np.clip(np.asarray(luma, dtype=np.float32), 0, 1) * 170 + 40
    grey = cv2.resize(grey, size, interpolation=cv2.INTER_AREA) if k < 1 else grey
    tint = np.zeros((*single.shape, 3), np.float32)
    tint[informative & single] = SINGLE
    tint[informative & ~single] = DOUBLE
    weight = np.where(informative, 0.45, 0.0).astype(np.float32)
    full = (single.shape[1] * 8, single.shape[0] * 8)
    tint = cv2.resize(cv2.resize(tint, full, interpolation=cv2.INTER_NEAREST)[:h, :w], size,
                      interpolation=cv2.INTER_AREA)
    weight = cv2.resize(cv2.resize(weight, full, interpolation=cv2.INTER_NEAREST)[:h, :w], size,
                        interpolation=cv2.INTER_AREA)[..., None]
    rgb = grey[..., None] * (1 - weight) + tint * weight
    img = Image.fromarray(np.clip(rgb, 0, 255).astype(np.uint8))
    draw = ImageDraw.Draw(img)
    for win in details.get("windows") or []:
        x0, y0 = 8 * win["col"] * k, 8 * win["row"] * k
        side = 8 * win["size"] * k
        draw.rectangle([x0, y0, x0 + side, y0 + side], outline=WINDOW, width=2)
    return figure_png(img)
