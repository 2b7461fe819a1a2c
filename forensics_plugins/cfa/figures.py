"""The map of the CFA finding for the report: the photo with every block's vote and the regions.

Drawn from the finding's ``details`` and the photo alone, so a report can be
rebuilt from ``findings.json`` and the evidence. The photo is reduced before
anything is drawn, so the cost does not grow with its resolution.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from PIL import Image, ImageDraw, ImageFont
from scipy import ndimage

from forensics_core.report import display_image, figure_png

MAP_MAX_SIDE = 1200

# RGBA tint of a block by its vote: the image's phase is left clear so the
# disagreeing blocks stand out; blocks that cannot vote are greyed.
VOTE_COLOURS = {
    "agree": (0, 0, 0, 0),
    "diagonal": (230, 40, 40, 150),
    "red_blue": (250, 160, 0, 150),
    "unusable": (90, 90, 90, 110),
}
REGION_COLOUR = (0, 200, 255)
_LEGEND = (
    ("agree", "same phase as the photo"),
    ("diagonal", "green on the other diagonal"),
    ("red_blue", "red and blue swapped"),
    ("unusable", "no vote (flat or clipped)"),
)


def vote_classes(shift_votes: np.ndarray) -> np.ndarray:
    """Class of each block's vote: 0 agree, 1 diagonal, 2 red/blue, 3 unusable; shape (ny, nx)."""
    sv = np.asarray(shift_votes)
    return np.select([sv == 0, (sv == 1) | (sv == 2), sv == 3], [0, 1, 2], default=3)


def map_png(pixels: np.ndarray, details: Mapping[str, Any]) -> bytes:
    """The photo with each block tinted by its vote and the detected regions outlined and numbered.

    Parameters
    ----------
    pixels : ndarray, shape (H, W) or (H, W, C)
        The evidence's stored grid.
    details : mapping
        The finding's details: ``block_px``, ``grid``, ``shift_votes`` and ``regions``.

    Returns
    -------
    bytes
        PNG, the photo's longest side at most :data:`MAP_MAX_SIDE` pixels, with a legend below.
    """
    img, factor = display_image(pixels, MAP_MAX_SIDE, 0.7, 30)
    block = int(details["block_px"])
    ny, nx = details["grid"]
    size = (max(1, round(nx * block * factor)), max(1, round(ny * block * factor)))
    classes = vote_classes(np.asarray(details["shift_votes"]))
    palette = np.array([VOTE_COLOURS[k] for k, _ in _LEGEND], dtype=np.uint8)
    tint = Image.fromarray(palette[classes], "RGBA").resize(size, Image.Resampling.NEAREST)
    canvas = img.convert("RGBA")
    layer = Image.new("RGBA", canvas.size, (0, 0, 0, 0))
    layer.paste(tint, (0, 0))
    canvas = Image.alpha_composite(canvas, layer)

    draw = ImageDraw.Draw(canvas)
    width = max(2, round(max(canvas.size) / 300))
    regions = details.get("regions", [])
    if regions:
        labels = np.zeros((ny, nx), dtype=np.uint8)
        for region in regions:
            rows, cols = np.asarray(region["blocks"], dtype=int).reshape(-1, 2).T
            labels[rows, cols] = min(region["id"], 255)
        big = np.asarray(Image.fromarray(labels).resize(size, Image.Resampling.NEAREST))
        edge = np.zeros(big.shape, dtype=bool)
        edge[:, 1:] |= big[:, 1:] != big[:, :-1]
        edge[1:, :] |= big[1:, :] != big[:-1, :]
        edge = ndimage.maximum_filter(edge, size=width)
        outline = Image.new("RGBA", size, REGION_COLOUR + (255,))
        canvas.paste(outline, (0, 0), Image.fromarray(edge.astype(np.uint8) * 255))
    font = ImageFont.load_default(size=max(12, round(max(canvas.size) / 45)))
    for region in regions:
        x0, y0 = region["bbox_px"][0] * factor, region["bbox_px"][1] * factor
        label = str(region["id"])
        box = draw.textbbox((x0 + width, y0 + width), label, font=font)
        draw.rectangle((box[0] - 2, box[1] - 1, box[2] + 2, box[3] + 1), fill=(255, 255, 255, 255))
        draw.text((x0 + width, y0 + width), label, fill=REGION_COLOUR, font=font)

    out = _with_legend(canvas.convert("RGB"))
    return figure_png(out)


def _with_legend(img: Image.Image) -> Image.Image:
    """``img`` with the colour legend below it, wrapped to its width."""
    size = max(12, round(img.width / 70))
    font = ImageFont.load_default(size=size)
    probe = ImageDraw.Draw(img)
    items = [(key, text, 2 * size + round(probe.textlength(text, font=font))) for key, text in
             _LEGEND + (("region", "detected region"),)]
    rows: list[list[tuple[str, str, int]]] = [[]]
    used = 6
    for item in items:
        if rows[-1] and used + item[2] > img.width:
            rows.append([])
            used = 6
        rows[-1].append(item)
        used += item[2]
    line = round(1.6 * size)
    out = Image.new("RGB", (img.width, img.height + line * len(rows) + 4), (255, 255, 255))
    out.paste(img, (0, 0))
    draw = ImageDraw.Draw(out)
    for r, row in enumerate(rows):
        x, y = 6, img.height + 5 + line * r
        for key, text, width in row:
            box = (x, y, x + size, y + size)
            if key == "agree":
                draw.rectangle(box, outline=(120, 120, 120))
            else:
                draw.rectangle(box, fill=REGION_COLOUR if key == "region" else VOTE_COLOURS[key][:3])
            draw.text((x + round(1.3 * size), y - 1), text, fill=(40, 40, 40), font=font)
            x += width
    return out
