"""Per-pixel votes for a JPEG grid origin from the zero counts.

ZERO (Nikoukhah et al., CVPRW 2019; IPOL 2021): each pixel lies in 64
blocks of 8x8, one per grid origin ``(x mod 8, y mod 8)`` of the block's
top-left corner; it votes for the origin of the block with the most zeros. It
casts no vote when two or more blocks tie for the maximum, nor when the block
with the maximum is flat (constant along x or y, :func:`.zeros.flat_blocks`):
flat blocks have zeros on every grid, so in sky, clipped highlights or
stripes the maximum says nothing about the compression. Pixels within 7 of a
border lie in fewer than 64 blocks and do not vote.

The 8x8 maximum is separable: the maximum over the 8 blocks of a row of
candidates, then over the 8 rows. The vote is unique exactly when one row
holds the overall maximum and that row's maximum is itself unique.
"""

from __future__ import annotations

import numba as nb
import numpy as np

NO_VOTE = -1


def grid_code(dx: int, dy: int) -> int:
    """Index 0-63 of the grid origin ``(dx, dy)``: ``8 * dy + dx``."""
    return 8 * (dy % 8) + (dx % 8)


def grid_origin(code: int) -> tuple[int, int]:
    """The grid origin ``(dx, dy)`` of a code from :func:`grid_code`."""
    return code % 8, code // 8


@nb.njit(cache=True)
def _votes(z, flat):
    nh, nw = z.shape
    h, w = nh + 7, nw + 7
    row_max = np.zeros((nh, w), np.int16)
    row_arg = np.zeros((nh, w), np.int32)
    row_unique = np.zeros((nh, w), np.bool_)
    for y in range(nh):
        for x in range(7, nw):
            best = -1
            arg = -1
            unique = False
            for bx in range(x - 7, x + 1):
                c = np.int16(z[y, bx])
                if c > best:
                    best = c
                    arg = bx
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
            for by in range(y - 7, y + 1):
                m = row_max[by, x]
                if m > best:
                    best = m
                    best_row = by
                    rows_at_best = 1
                elif m == best:
                    rows_at_best += 1
            if rows_at_best == 1 and row_unique[best_row, x]:
                bx = row_arg[best_row, x]
                if not flat[best_row, bx]:
                    out[y, x] = 8 * (best_row % 8) + bx % 8
    return out


def vote_map(counts: np.ndarray, flat: np.ndarray) -> np.ndarray:
    """Each pixel's vote for the grid origin of its block with the most zeros.

    Parameters
    ----------
    counts : ndarray, shape (H - 7, W - 7), uint8
        Zero counts from :func:`.zeros.zero_counts`.
    flat : ndarray, shape (H - 7, W - 7), bool
        Flat blocks from :func:`.zeros.flat_blocks`.

    Returns
    -------
    ndarray, shape (H, W), int8
        Grid code 0-63 (see :func:`grid_code`), or :data:`NO_VOTE` for a tie,
        a flat best block, and pixels within 7 of a border.

    References
    ----------
    T. Nikoukhah, J. Anger, M. Colom, J.-M. Morel, R. Grompone von Gioi, ZERO: a Local JPEG Grid Origin Detector
    Based on the Number of DCT Zeros and its Applications in Image Forensics, IPOL 11 (2021), pp. 396-433.
    """
    if counts.shape != flat.shape:
        raise ValueError(f"counts {counts.shape} and flat {flat.shape} differ in shape")
    return _votes(np.ascontiguousarray(counts), np.ascontiguousarray(flat, dtype=bool))
