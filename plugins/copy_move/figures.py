"""The copy_move figure: the photo with the matched keypoints, the identical windows and their sources.

Drawn from the finding's ``details`` and the photo alone, so the report can be
rebuilt from ``findings.json`` and the evidence; the photo is reduced first.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import cv2
import numpy as np
from PIL import Image, ImageDraw

from forensics_core.report import figure_png

from .spec import GRAIN

MAX_SIDE = 1200
TARGET = (230, 40, 40)
SOURCE = (40, 120, 255)
LINK = (255, 210, 0)


def overlay_png(luma: np.ndarray, details: Mapping[str, Any]) -> bytes:
    """PNG of the dimmed photo: the best hypothesis' matches (yellow lines; for a move found by the grain, the outlines of
    its two areas), identical windows (red) and sources (blue)."""
    h, w = luma.shape
    k = min(1.0, MAX_SIDE / max(h, w))
    grey = np.clip(np.asarray(luma, dtype=np.float32), 0, 1) * 200 + 20
    if k < 1:
        grey = cv2.resize(grey, (max(1, round(w * k)), max(1, round(h * k))), interpolation=cv2.INTER_AREA)
    img = Image.fromarray(grey.astype(np.uint8)).convert("RGB")
    draw = ImageDraw.Draw(img, "RGBA")
    best = next((x for x in details.get("hypotheses") or [] if x["id"] == details.get("best")), None)
    if best is not None:
        back = cv2.invertAffineTransform(np.asarray(best["matrix_px"], dtype=np.float64))
        for x, y, size, _ in best["identical_windows_px"]:
            square = np.array([[x, y], [x + size, y], [x + size, y + size], [x, y + size]])
            source = square @ back[:, :2].T + back[:, 2]
            draw.polygon([tuple(p) for p in (square * k)], fill=TARGET + (90,), outline=TARGET + (255,))
            draw.polygon([tuple(p) for p in (source * k)], fill=SOURCE + (90,), outline=SOURCE + (255,))
        if best.get("found_by") == GRAIN:
            for outline, colour in ((best["source_px"], SOURCE), (best["target_px"], TARGET)):
                draw.polygon([(x * k, y * k) for x, y in outline], outline=colour + (255,))
            return figure_png(img)
        for (sx, sy), (tx, ty) in zip(best["source_px"], best["target_px"]):
            draw.line([(sx * k, sy * k), (tx * k, ty * k)], fill=LINK + (200,), width=1)
            draw.ellipse([tx * k - 2, ty * k - 2, tx * k + 2, ty * k + 2], outline=TARGET + (255,))
            draw.ellipse([sx * k - 2, sy * k - 2, sx * k + 2, sy * k + 2], outline=SOURCE + (255,))
    return figure_png(img)
