"""The prnu figure: the photo, dimmed, tinted where blocks lack the fingerprint, the flagged regions outlined."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import cv2
import numpy as np
from PIL import Image, ImageDraw

from forensics_core.report import figure_png

MAX_SIDE = 1200
MISSING = np.array([230, 40, 40], np.float32)
PRESENT = np.array([40, 160, 90], np.float32)
REGION = (255, 210, 0)
# Block log-likelihood ratio (natural log) at which the tint is full.
_FULL_TINT = 4.0


def local_map_png(luma: np.ndarray, local: Mapping[str, Any]) -> bytes:
    """PNG of the dimmed photo: red where a block's correlation says "no fingerprint", green where it says
    "fingerprint", untinted where undecidable; flagged regions outlined in yellow.

    Parameters
    ----------
    luma : ndarray, shape (H, W)
        In [0, 1].
    local : mapping
        The finding's ``details["local"]``: ``grid`` (block LLRs, stored grid), ``regions`` (boxes, pixels).
    """
    h, w = luma.shape
    k = min(1.0, MAX_SIDE / max(h, w))
    size = (max(1, round(w * k)), max(1, round(h * k)))
    grey = np.clip(np.asarray(luma, dtype=np.float32), 0, 1) * 170 + 40
    grey = cv2.resize(grey, size, interpolation=cv2.INTER_AREA) if k < 1 else grey
    grid = np.asarray(local["grid"]["llr"], np.float32)
    block, step = local["grid"]["block"], local["grid"]["step"]
    # Each block's value at its centre, spread over the grid step.
    cells = np.zeros((h, w), np.float32)
    half = (block - step) // 2
    cy, cx = grid.shape
    cells[half: half + cy * step, half: half + cx * step] = np.kron(grid, np.ones((step, step), np.float32))[
        : h - half, : w - half]
    cells = cv2.resize(cells, size, interpolation=cv2.INTER_NEAREST) if k < 1 else cells
    strength = np.clip(np.abs(cells) / _FULL_TINT, 0, 1)[..., None] * 0.6
    tint = np.where((cells > 0)[..., None], MISSING, PRESENT)
    rgb = grey[..., None] * (1 - strength) + tint * strength
    image = Image.fromarray(np.clip(rgb, 0, 255).astype(np.uint8))
    draw = ImageDraw.Draw(image)
    for x0, y0, x1, y1 in local.get("regions", []):
        draw.rectangle([x0 * k, y0 * k, x1 * k, y1 * k], outline=REGION, width=3)
    return figure_png(image)
