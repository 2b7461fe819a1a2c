"""The copy_move figures: the photo with the matched keypoints, the identical windows and their sources; and the two
regions side by side, enlarged, with their difference.

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

from .detector import best_hypothesis
from .spec import GRAIN

MAX_SIDE = 1200
# Side of each enlarged region: matched regions are often a few dozen pixels
# across, too small on the page to tell an object from a printed pattern.
REGION_SIDE = 400
# The difference of the two regions is drawn around mid-grey at this gain,
# fixed so that figures of different photos read alike: the compression
# noise a copy differs from its source by shows as a faint grain, shading
# and detail that differ as shapes.
DIFFERENCE_GAIN = 4.0
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
    best = best_hypothesis(details)
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


def regions_png(luma: np.ndarray, details: Mapping[str, Any]) -> bytes | None:
    """PNG of the best candidate's two regions side by side, enlarged, and their difference: left the target region
    (the box around its identical windows), middle the source region mapped onto it by the transform, right the
    target less the mapped source, times :data:`DIFFERENCE_GAIN` around mid-grey; None when no window is identical.

    What the grain test cannot tell, printed or manufactured repetition (a mesh, wallpaper, two prints of one
    picture) from a copy, the examiner often can from these views: a copy differs from its source by the
    compression's noise alone, over an area the tool that made it leaves (a brush's blob, a pasted rectangle),
    whereas two objects in the scene differ in shading, detail and what shows between their parts.
    """
    best = best_hypothesis(details)
    if best is None or not best["identical_windows_px"]:
        return None
    windows = np.asarray(best["identical_windows_px"], dtype=np.float64)
    margin = windows[0, 2]
    h, w = luma.shape
    x0, y0 = (max(0, int(v - margin)) for v in windows[:, :2].min(axis=0))
    x1 = min(w, int((windows[:, 0] + windows[:, 2]).max() + margin))
    y1 = min(h, int((windows[:, 1] + windows[:, 2]).max() + margin))
    grey = np.clip(np.asarray(luma, dtype=np.float32), 0, 1) * 255
    matrix = np.asarray(best["matrix_px"], dtype=np.float64).copy()
    matrix[:, 2] -= (x0, y0)
    source = cv2.warpAffine(grey, matrix, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR)
    k = REGION_SIDE / max(x1 - x0, y1 - y0)
    size = (max(1, round((x1 - x0) * k)), max(1, round((y1 - y0) * k)))
    target = grey[y0:y1, x0:x1]
    difference = np.clip(128.0 + DIFFERENCE_GAIN * (target - source), 0, 255)
    views = [cv2.resize(v, size, interpolation=cv2.INTER_NEAREST) for v in (target, source, difference)]
    gap = 12
    out = Image.new("RGB", (3 * size[0] + 2 * gap, size[1]), (255, 255, 255))
    for i, (view, colour) in enumerate(zip(views, (TARGET, SOURCE, (128, 128, 128)))):
        tile = Image.fromarray(view.astype(np.uint8)).convert("RGB")
        ImageDraw.Draw(tile).rectangle([0, 0, size[0] - 1, size[1] - 1], outline=colour, width=3)
        out.paste(tile, (i * (size[0] + gap), 0))
    return figure_png(out)
