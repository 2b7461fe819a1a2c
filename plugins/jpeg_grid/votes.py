"""Per-pixel votes for a JPEG grid origin from the zero counts.

ZERO (Nikoukhah et al., CVPRW 2019): each pixel lies in 64 blocks of
8x8, one per grid origin ``(x mod 8, y mod 8)`` of the block's top-left
corner; it votes for the origin of the block with the most zeros, and for
none when two or more blocks tie for the maximum (flat or saturated areas,
where every block is all zeros).

The 8x8 maximum is separable: the maximum over the 8 blocks of a row of
candidates, then over the 8 rows. The vote is unique exactly when one row
holds the overall maximum and that row's maximum is itself unique.

Pixels whose blocks contain a clipped pixel (0 or 255) do not vote at all:
clipping after the decoder's inverse DCT destroys the zeros of the blocks it
touches, so near blown highlights or crushed shadows the counts are noise,
and such pixels would otherwise look like a region missing the grid.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from scipy import ndimage

NO_VOTE = -1
VOID = -2


def grid_code(dx: int, dy: int) -> int:
    """Index 0-63 of the grid origin ``(dx, dy)``: ``8 * dy + dx``."""
    return 8 * (dy % 8) + (dx % 8)


def grid_origin(code: int) -> tuple[int, int]:
    """The grid origin ``(dx, dy)`` of a code from :func:`grid_code`."""
    return code % 8, code // 8


@nb.njit(cache=True)
def _votes(z, excluded, void):
    nh, nw = z.shape
    h, w = nh + 7, nw + 7
    row_max = np.empty((nh, w), np.int16)
    row_arg = np.empty((nh, w), np.int8)
    row_unique = np.empty((nh, w), np.bool_)
    for y in range(nh):
        gy = y % 8
        for x in range(7, nw):
            best = -1
            arg = -1
            unique = False
            for i in range(8):
                bx = x - i
                c = np.int16(z[y, bx])
                if 8 * gy + bx % 8 == excluded:
                    continue
                if c > best:
                    best = c
                    arg = bx % 8
                    unique = True
                elif c == best:
                    unique = False
            row_max[y, x] = best
            row_arg[y, x] = arg
            row_unique[y, x] = unique
    out = np.full((h, w), NO_VOTE, np.int8)
    for y in range(7, nh):
        for x in range(7, nw):
            best = -1
            best_row = -1
            rows_at_best = 0
            for j in range(8):
                m = row_max[y - j, x]
                if m > best:
                    best = m
                    best_row = y - j
                    rows_at_best = 1
                elif m == best:
                    rows_at_best += 1
            if void[y, x]:
                out[y, x] = VOID
            elif rows_at_best == 1 and row_unique[best_row, x]:
                out[y, x] = 8 * (best_row % 8) + row_arg[best_row, x]
    return out


def clipped_neighbourhood(luminance: np.ndarray) -> np.ndarray:
    """Pixels lying in a block that holds a clipped pixel, shape (H, W), bool.

    A pixel lies in the 64 blocks whose top-left corners are up to 7 pixels
    above and left of it, which together cover the 15x15 square centred on it.
    """
    clipped = (luminance <= 0) | (luminance >= 255)
    return ndimage.maximum_filter(clipped, size=15, mode="constant", cval=False)


def vote_map(counts: np.ndarray, excluded: int | None = None, void: np.ndarray | None = None) -> np.ndarray:
    """Each pixel's vote for the grid origin of its block with the most zeros.

    Parameters
    ----------
    counts : ndarray, shape (H - 7, W - 7)
        Zero counts from :func:`.zeros.zero_counts`.
    excluded : int, optional
        Grid code (see :func:`grid_code`) left out of the competition: with the
        main grid excluded, each pixel votes for the best of the other 63.
    void : ndarray, shape (H, W), bool, optional
        Pixels that do not vote (:func:`clipped_neighbourhood`).

    Returns
    -------
    ndarray, shape (H, W), int8
        Grid code 0-63; :data:`VOID` where ``void``; :data:`NO_VOTE` for a tie
        and for pixels within 7 of the top or left border or 8 of the bottom
        or right border, which lie in fewer than 64 blocks.
    """
    shape = (counts.shape[0] + 7, counts.shape[1] + 7)
    void = np.zeros(shape, bool) if void is None else np.ascontiguousarray(void, dtype=bool)
    if void.shape != shape:
        raise ValueError(f"void has shape {void.shape}, expected {shape}")
    return _votes(np.ascontiguousarray(counts), -1 if excluded is None else int(excluded), void)


@nb.njit(cache=True)
def _cell_tally(v, cell):
    h, w = v.shape
    hc, wc = h // cell, w // cell
    hist = np.zeros((hc, wc, 64), np.uint16)
    eligible = np.zeros((hc, wc), np.uint16)
    for y in range(hc * cell):
        inside_y = 7 <= y <= h - 8
        for x in range(wc * cell):
            g = v[y, x]
            if not (inside_y and 7 <= x <= w - 8) or g == VOID:
                continue
            cy, cx = y // cell, x // cell
            eligible[cy, cx] += 1
            if g >= 0:
                hist[cy, cx, g] += 1
    return hist, eligible


def cell_tally(votes: np.ndarray, cell: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Votes per grid origin in each ``cell`` x ``cell`` tile of the vote map.

    Parameters
    ----------
    votes : ndarray, shape (H, W), int8
        From :func:`vote_map`.
    cell : int
        Tile side, pixels (at most 255, so a tile's counts fit 16 bits).

    Returns
    -------
    hist : ndarray, shape (H // cell, W // cell, 64), uint16
        Number of votes for each grid code in each tile.
    eligible : ndarray, shape (H // cell, W // cell), uint16
        Pixels of each tile that could vote (those lying in 64 blocks, not
        void), whether they voted or tied.
    """
    return _cell_tally(np.ascontiguousarray(votes), int(cell))
