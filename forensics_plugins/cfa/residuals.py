"""Stage 1: per-block energies of linear prediction residuals at the four positions of the 2 x 2 cell.

Demosaicing computes two of every pixel's three colours from its neighbours,
so the prediction error of a pixel from its neighbours depends on whether the
sensor sampled that colour there or interpolated it (Popescu & Farid, 2005,
sec. III; Kirchner, 2010, sec. 2). The pattern repeats every 2 pixels in
both directions, so every statistic is split by the position ``(y mod 2,
x mod 2)`` of the pixel in the 2 x 2 cell.

For each block of ``B x B`` pixels (B even, blocks aligned with the cell) and
each of the four positions ``p`` this module measures, for ten residual
images, the mean absolute residual

.. math::  e_{f,p} = \\frac{4}{B^2} \\sum_{(y, x) \\in \\text{block}, (y, x) \\equiv p} |(s_f - K_f * s_f)(y, x)|

where ``s_f`` is one of R, G, B, R - G, B - G (colour differences, which
edge-aware demosaicing interpolates, e.g. Hamilton & Adams 1997) and ``K_f``
the mean of the four horizontal and vertical neighbours ("cross") or of the
four diagonal ones ("diag"). The feature of the block is
``log(e + offset)`` centred over the four positions: only how the positions
differ matters, not the block's overall texture or noise level.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

FEATURES = (
    ("R", "cross"), ("G", "cross"), ("B", "cross"), ("R-G", "cross"), ("B-G", "cross"),
    ("R", "diag"), ("G", "diag"), ("B", "diag"), ("R-G", "diag"), ("B-G", "diag"),
)
"""The residual images, as (source, predictor) pairs, in the feature order."""

POSITIONS = ((0, 0), (0, 1), (1, 0), (1, 1))
"""Positions ``(y mod 2, x mod 2)`` in the 2 x 2 cell, in the feature order."""


@dataclass(frozen=True)
class BlockFeatures:
    """Residual features of every block.

    Attributes
    ----------
    features : ndarray of float32, shape (ny, nx, F, 4)
        ``log(e + offset)`` centred over the four positions (F features, see ``names``).
    clipped : ndarray of float32, shape (ny, nx)
        Fraction of the block's pixels left out because a channel of theirs
        or of a neighbour is at 0 or at full scale (the largest over the four
        positions).
    activity : ndarray of float32, shape (ny, nx)
        Mean absolute cross residual of G over the block, in 8-bit units.
    colour : ndarray of float32, shape (ny, nx)
        Colour balance ``log1p(mean R) - log1p(mean B)`` (8-bit units), which
        a shift of the mosaic does not change.
    green : ndarray of float32, shape (ny, nx)
        Green excess ``log1p(mean G) - (log1p(mean R) + log1p(mean B)) / 2``
        (8-bit units): with ``colour``, the block's chromaticity.
    names : tuple of (str, str)
        The features, as (source, predictor) pairs.
    block_px : int
        Block side, pixels.
    """

    features: np.ndarray
    clipped: np.ndarray
    activity: np.ndarray
    colour: np.ndarray
    green: np.ndarray
    names: tuple[tuple[str, str], ...]
    block_px: int


# Rows of pixels computed at once: bounds the working memory (a few arrays of
# this many rows, three channels, float32) whatever the photo's size.
_STRIP_PX = 64


def _mirrored(index: np.ndarray, size: int) -> np.ndarray:
    """Indices one step outside ``[0, size)`` reflected without repeating the edge (keeps the cell phase)."""
    index = np.abs(index)
    return np.where(index >= size, 2 * size - 2 - index, index)


def _cell_sums(a: np.ndarray, block: int, out: np.ndarray) -> None:
    """Sums of ``a`` over each block's pixels at each position of the 2 x 2 cell.

    ``a`` has shape (rows, cols), both multiples of ``block``; ``out``, shape
    (rows // block, cols // block, 4) with the positions in
    :data:`POSITIONS` order, is filled in place. The pixels of one position
    in a block are every other one, so each sum adds strided slices of ``a``
    (faster than reducing a reshaped array over its short axes).
    """
    for px in range(2):
        column = a[:, px::block].copy()
        for k in range(px + 2, block, 2):
            column += a[:, k::block]
        for py in range(2):
            cell = out[:, :, 2 * py + px]
            np.copyto(cell, column[py::block])
            for k in range(py + 2, block, 2):
                cell += column[k::block]


def _accumulate(rgb: np.ndarray, block: int, ny: int, nx: int,
                scale: np.float32) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sums of |residual| per block, feature and position over the whole blocks, in strips of rows.

    A pixel is left out when any channel of it or of its eight neighbours is
    at 0 or full scale: clipping flattens the residuals of the samples and of
    the interpolated values unequally, which would bend the pattern. Returns,
    in 8-bit units (values times ``scale``), float32: ``sums`` (ny, nx, 10, 4)
    and ``counts`` (ny, nx, 4) of the pixels kept, and ``colour`` (ny, nx, 3)
    sums of R, B and G over all pixels. The values must be finite (the
    detector refuses other photos). For 8-bit photos the values are
    multiples of 1/4, and their sums over blocks of up to 128 pixels stay
    below 2^24 quarters, so float32 adds them exactly, in any order.
    """
    h, w = rgb.shape[:2]
    sums = np.empty((ny, nx, len(FEATURES), 4), np.float32)
    counts = np.empty((ny, nx, 4), np.float32)
    colour = np.empty((ny, nx, 3), np.float32)
    top, quarter, zero = np.float32(254.5), np.float32(0.25), np.float32(0.0)
    cols = _mirrored(np.arange(-1, nx * block + 1), w)
    step = max(1, _STRIP_PX // block) * block
    for y0 in range(0, ny * block, step):
        y1 = min(ny * block, y0 + step)
        b0, b1 = y0 // block, y1 // block
        # The strip with a one-pixel ring of neighbours, channels first.
        rows = _mirrored(np.arange(y0 - 1, y1 + 1), h)
        v = np.ascontiguousarray(np.take(np.take(rgb, rows, axis=0)[..., :3], cols, axis=1).transpose(2, 0, 1),
                                 dtype=np.float32)
        if scale != 1.0:
            v *= scale
        clip = (v[0] <= zero) | (v[0] >= top) | (v[1] <= zero) | (v[1] >= top) | (v[2] <= zero) | (v[2] >= top)
        bad = (clip[:-2, :-2] | clip[:-2, 1:-1] | clip[:-2, 2:] | clip[1:-1, :-2] | clip[1:-1, 1:-1]
               | clip[1:-1, 2:] | clip[2:, :-2] | clip[2:, 1:-1] | clip[2:, 2:])
        keep = (~bad).astype(np.float32)
        centre = v[:, 1:-1, 1:-1]
        neighbours = ((v[:, :-2, 1:-1], v[:, 2:, 1:-1], v[:, 1:-1, :-2], v[:, 1:-1, 2:]),  # cross
                      (v[:, :-2, :-2], v[:, :-2, 2:], v[:, 2:, :-2], v[:, 2:, 2:]))        # diag
        for k, (a, b, c, d) in enumerate(neighbours):
            res = a + b
            res += c
            res += d
            res *= quarter
            np.subtract(centre, res, out=res)
            res *= keep
            planes = (res[0], res[1], res[2], res[0] - res[1], res[2] - res[1])
            for f, plane in enumerate(planes):
                _cell_sums(np.abs(plane), block, sums[b0:b1, :, 5 * k + f])
        _cell_sums(keep, block, counts[b0:b1])
        per_position = np.empty((b1 - b0, nx, 4), np.float32)
        for i, channel in enumerate((0, 2, 1)):
            _cell_sums(centre[channel], block, per_position)
            colour[b0:b1, :, i] = per_position.sum(axis=2)
    return sums, counts, colour


def block_features(rgb: np.ndarray, block: int, full_scale: float, offset: float) -> BlockFeatures:
    """Compute the residual features of every whole block of an RGB image.

    Parameters
    ----------
    rgb : ndarray, shape (H, W, C), C >= 3
        The stored grid (channels R, G, B first), any numeric dtype, values in
        ``[0, full_scale]``. Read only.
    block : int
        Block side in pixels, even.
    full_scale : float
        The value of a saturated channel (255 for 8-bit photos); residuals are
        expressed in 8-bit units (``255 / full_scale`` per stored unit).
    offset : float
        Added to the mean absolute residual (8-bit units) before the
        logarithm, so flat or clipped blocks do not dominate.

    Returns
    -------
    BlockFeatures
        Covering the ``H // block`` x ``W // block`` blocks from the top-left
        corner; the remaining right and bottom margins are not used.
    """
    if block < 2 or block % 2:
        raise ValueError(f"block side must be an even number of pixels, not {block}")
    h, w = rgb.shape[:2]
    ny, nx = h // block, w // block
    names = FEATURES
    sums, counts, colour = _accumulate(rgb, block, ny, nx, np.float32(255.0 / full_scale))
    means = sums / np.maximum(counts, 1.0)[:, :, None, :]
    activity = means[:, :, names.index(("G", "cross"))].mean(axis=2)
    logs = np.log(means + np.float32(offset))
    balance = np.log1p(colour / np.float32(block * block))
    return BlockFeatures(
        features=logs - logs.mean(axis=3, keepdims=True),
        clipped=1.0 - counts.min(axis=2) / np.float32(block * block / 4),
        activity=activity,
        colour=balance[:, :, 0] - balance[:, :, 1],
        green=balance[:, :, 2] - 0.5 * (balance[:, :, 0] + balance[:, :, 1]),
        names=names,
        block_px=block,
    )
