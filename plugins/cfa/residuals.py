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

import numba as nb
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


def _mirrored(index: np.ndarray, size: int) -> np.ndarray:
    """Indices one step outside ``[0, size)`` reflected without repeating the edge (keeps the cell phase)."""
    index = np.abs(index)
    return np.where(index >= size, 2 * size - 2 - index, index)


@nb.njit(cache=True, nogil=True)
def _clipped(value, top):
    return value <= 0.0 or value >= top


@nb.njit(cache=True, nogil=True)
def _accumulate(rgb, block, ny, nx, scale, up, down, left, right, sums, counts, colour):
    """One pass over the pixels of the whole blocks: sums of |residual| per block, feature and position.

    ``up``/``down``/``left``/``right`` hold each row's or column's mirrored
    neighbour index. A pixel is left out when any channel of it or of its
    eight neighbours is at 0 or full scale: clipping flattens the residuals
    of the samples and of the interpolated values unequally, which would bend
    the pattern. Filled in place, in 8-bit units (values times ``scale``):
    ``sums`` (ny, nx, 10, 4) and ``counts`` (ny, nx, 4) of the pixels kept,
    and ``colour`` (ny, nx, 3) sums of R, B and G over all pixels.
    """
    cross = np.empty(3, np.float32)
    diag = np.empty(3, np.float32)
    top = np.float32(254.5)
    quarter = np.float32(0.25)
    for y in range(ny * block):
        by = y // block
        pos_y = 2 * (y % 2)
        ya, yb = up[y], down[y]
        for x in range(nx * block):
            xa, xb = left[x], right[x]
            bx = x // block
            colour[by, bx, 0] += np.float32(rgb[y, x, 0]) * scale
            colour[by, bx, 1] += np.float32(rgb[y, x, 2]) * scale
            colour[by, bx, 2] += np.float32(rgb[y, x, 1]) * scale
            sat = False
            for c in range(3):
                v = np.float32(rgb[y, x, c]) * scale
                n, s_, w, e = (np.float32(rgb[ya, x, c]) * scale, np.float32(rgb[yb, x, c]) * scale,
                               np.float32(rgb[y, xa, c]) * scale, np.float32(rgb[y, xb, c]) * scale)
                nw, ne, sw, se = (np.float32(rgb[ya, xa, c]) * scale, np.float32(rgb[ya, xb, c]) * scale,
                                  np.float32(rgb[yb, xa, c]) * scale, np.float32(rgb[yb, xb, c]) * scale)
                if (_clipped(v, top) or _clipped(n, top) or _clipped(s_, top) or _clipped(w, top)
                        or _clipped(e, top) or _clipped(nw, top) or _clipped(ne, top) or _clipped(sw, top)
                        or _clipped(se, top)):
                    sat = True
                    break
                cross[c] = v - quarter * (n + s_ + w + e)
                diag[c] = v - quarter * (nw + ne + sw + se)
            if sat:
                continue
            pos = pos_y + (x % 2)
            counts[by, bx, pos] += 1.0
            s = sums[by, bx]
            s[0, pos] += abs(cross[0])
            s[1, pos] += abs(cross[1])
            s[2, pos] += abs(cross[2])
            s[3, pos] += abs(cross[0] - cross[1])
            s[4, pos] += abs(cross[2] - cross[1])
            s[5, pos] += abs(diag[0])
            s[6, pos] += abs(diag[1])
            s[7, pos] += abs(diag[2])
            s[8, pos] += abs(diag[0] - diag[1])
            s[9, pos] += abs(diag[2] - diag[1])


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
    sums = np.zeros((ny, nx, len(names), 4), dtype=np.float32)
    counts = np.zeros((ny, nx, 4), dtype=np.float32)
    colour = np.zeros((ny, nx, 3), dtype=np.float32)
    rows, cols = np.arange(h), np.arange(w)
    _accumulate(rgb, block, ny, nx, np.float32(255.0 / full_scale),
                _mirrored(rows - 1, h), _mirrored(rows + 1, h), _mirrored(cols - 1, w), _mirrored(cols + 1, w),
                sums, counts, colour)
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
