"""Figures of the JPEG grid finding for the report.

Both are drawn from the finding's ``details`` (plus the photo for the map),
so a report can be rebuilt from ``findings.json`` and the evidence.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from forensics_core.report import display_image, figure_png

MAP_MAX_SIDE = 1200

MEANINGFUL = (220, 30, 30)
CANDIDATE = (245, 150, 20)


def tiles_mask(runs: list[list[int]], tiles_shape: tuple[int, int]) -> np.ndarray:
    """Boolean tile mask, shape ``tiles_shape``, from a region's ``tiles_rle`` runs ``[row, column, length]``."""
    mask = np.zeros(tiles_shape, bool)
    for row, col, length in runs:
        mask[row, col:col + length] = True
    return mask


def _outline(mask: np.ndarray) -> np.ndarray:
    inner = mask.copy()
    inner[1:-1, 1:-1] = mask[1:-1, 1:-1] & mask[:-2, 1:-1] & mask[2:, 1:-1] & mask[1:-1, :-2] & mask[1:-1, 2:]
    return mask & ~inner


def map_png(pixels: np.ndarray, details: Mapping[str, Any]) -> bytes:
    """The photo with the regions voting for another grid or lacking the main one, filled and numbered.

    Parameters
    ----------
    pixels : ndarray, shape (H, W) or (H, W, C)
        The evidence's stored grid.
    details : mapping
        The finding's details (``regions`` with ``tiles_rle``; ``map`` with
        the tile size and grid shape).

    Returns
    -------
    bytes
        PNG, longest side at most :data:`MAP_MAX_SIDE` pixels. Red: regions
        whose NFA is below the threshold; orange outline: the strongest
        candidates that are not.
    """
    img, factor = display_image(pixels, MAP_MAX_SIDE, 0.6, 40)
    geometry = details.get("map") or {}
    cell = int(geometry.get("cell_px", 8))
    tiles_shape = tuple(geometry.get("tiles_shape", (0, 0)))
    overlay = np.zeros((img.size[1], img.size[0], 4), np.uint8)
    labels = []
    for region in details.get("regions", []):
        tiles = tiles_mask(region["tiles_rle"], tiles_shape)
        # Tile masks are scaled to the display with nearest neighbour, so
        # every drawn pixel is one the analysis assigned to the region.
        scaled = np.asarray(Image.fromarray(tiles).resize(
            (max(1, round(tiles_shape[1] * cell * factor)), max(1, round(tiles_shape[0] * cell * factor))),
            Image.Resampling.NEAREST))[: img.size[1], : img.size[0]]
        colour = MEANINGFUL if region["meaningful"] else CANDIDATE
        h, w = scaled.shape
        if region["meaningful"]:
            overlay[:h, :w][scaled] = (*colour, 90)
        overlay[:h, :w][_outline(scaled)] = (*colour, 255)
        x0, y0 = region["bbox_px"][:2]
        what = "no main grid" if region["stage"] == "missing" else f"({region['grid'][0]}, {region['grid'][1]})"
        labels.append((x0 * factor + 3, y0 * factor + 3, f"{region['id']}: {what}", colour))
    img = Image.alpha_composite(img.convert("RGBA"), Image.fromarray(overlay, "RGBA")).convert("RGB")
    draw = ImageDraw.Draw(img)
    font = ImageFont.load_default(size=max(12, round(max(img.size) / 55)))
    for x, y, text, colour in labels:
        box = draw.textbbox((x, y), text, font=font)
        draw.rectangle((box[0] - 2, box[1] - 1, box[2] + 2, box[3] + 1), fill=(255, 255, 255))
        draw.text((x, y), text, fill=colour, font=font)
    return figure_png(img)


def vote_map_png(details: Mapping[str, Any], scale: int = 4) -> bytes:
    """Share of the votes for the main grid on blocks of tiles, black 0 % to white 100 %, regions outlined.

    Parameters
    ----------
    details : mapping
        The finding's details (``map.main_share_percent``, -1 where no pixel
        could vote, drawn dark blue).
    scale : int
        Display pixels per block.

    Returns
    -------
    bytes
        PNG.
    """
    geometry = details["map"]
    share = np.asarray(geometry["main_share_percent"], dtype=np.float64)
    grey = np.clip(share, 0, 100) / 100.0 * 255.0
    rgb = np.stack([grey, grey, grey], axis=-1)
    rgb[share < 0] = (20, 20, 90)
    block = int(geometry["block_tiles"])
    tiles_shape = tuple(geometry["tiles_shape"])
    for region in details.get("regions", []):
        tiles = tiles_mask(region["tiles_rle"], tiles_shape)
        hb, wb = share.shape
        pad = ((0, hb * block - tiles.shape[0]), (0, wb * block - tiles.shape[1]))
        blocks = np.pad(tiles, pad).reshape(hb, block, wb, block).any(axis=(1, 3))
        rgb[_outline(blocks)] = MEANINGFUL if region["meaningful"] else CANDIDATE
    img = Image.fromarray(rgb.astype(np.uint8)).resize((share.shape[1] * scale, share.shape[0] * scale),
                                                      Image.Resampling.NEAREST)
    return figure_png(img)


def regions_mask(details: dict[str, Any], shape: tuple[int, int]) -> np.ndarray:
    """Boolean ``(H, W)`` map of the pixels in the finding's meaningful regions (``JpegGrid.localize``)."""
    mask = np.zeros(shape, bool)
    cell = details["map"]["cell_px"]
    tiles_shape = tuple(details["map"]["tiles_shape"])
    for region in details.get("regions", []):
        if region["meaningful"]:
            tiles = tiles_mask(region["tiles_rle"], tiles_shape)
            up = np.kron(tiles, np.ones((cell, cell), bool))[: shape[0], : shape[1]]
            mask[: up.shape[0], : up.shape[1]] |= up
    return mask
