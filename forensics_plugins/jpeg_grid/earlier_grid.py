"""A second grid throughout the photo: compressed, cropped off the block grid, compressed again.

A photo compressed once, cropped at an offset that is not a multiple of 8
(or shifted) and saved again keeps the first compression's grid, moved by
the crop, wherever the second compression left its zeros: in smooth areas
all over the frame, strongly where the first compression was the coarser.
ZERO then finds regions voting for that grid, most in flat or smooth parts,
and reads them as pasted. A pasted piece's grid is found where the piece
is; the crop's grid is found in every part of the photo. So a grid ``g``
other than the main one is the photo's own earlier grid when, with its
regions and their surroundings set aside, it still leads the votes of the
other non-main grids (by ``LEAD`` times the next) in at least
``MIN_CELL_SHARE`` of the cells of a ``CELLS`` x ``CELLS`` partition of
the frame, or, its regions counted, in ``MIN_CELL_SHARE_ALL`` of them (a
region that spans the frame, as at quality 98 after a coarse first
compression, leaves nothing once set aside; a pasted piece covering three
quarters of the frame would be read as the photo's history). Its regions are then processing, not evidence; regions on any
other grid stay foreign, so a piece pasted into a cropped photo is still
reported.

Measured on the innocent-processing suite's crops (10 real camera photos,
JPEG 87-100): the crop's grid led in 10 of 16 cells where the first grid
survived (quality 96); the three strongest other grids of every crop led
in at most 1 of 16.

References
----------
.. [1] T. Nikoukhah, J. Anger, M. Colom, J.-M. Morel, R. Grompone von Gioi,
   ZERO: a local JPEG grid origin detector based on the number of DCT zeros
   and its applications in image forensics, IPOL 11 (2021).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .regions import W, Region

CELLS = 4
LEAD = 2.0
MIN_CELL_SHARE = 0.5
#: Its regions counted, it must lead in this share of the cells: where the earlier compression was coarse and the
#: later one fine (quality 98 and up), one region can span the frame, and setting it aside leaves nothing.
MIN_CELL_SHARE_ALL = 0.75
#: Candidates: the grids with the most votes besides the main one (a crop's earlier grid is among them).
CANDIDATES = 3
#: A cell needs this many votes for the candidate grid before its lead counts.
MIN_CELL_VOTES = 64


@dataclass(frozen=True)
class EarlierGrid:
    """The grid of a compression before a crop, found all over the photo.

    Attributes
    ----------
    grid : int
        Its grid code ``8 * dy + dx``.
    cells_led : int
        Cells of the partition where it leads the other non-main grids.
    cells : int
        Cells of the partition.
    explained : tuple of int
        Indices (into the regions given) of the regions voting for it.
    """

    grid: int
    cells_led: int
    cells: int
    explained: tuple[int, ...]


def _cell_counts(votes: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Votes per grid code in each cell of the partition, shape (CELLS * CELLS, 64)."""
    h, w = votes.shape
    rows = np.minimum(np.arange(h) * CELLS // h, CELLS - 1)
    cols = np.minimum(np.arange(w) * CELLS // w, CELLS - 1)
    cell = rows[:, None] * CELLS + cols[None, :]
    ok = keep & (votes >= 0)
    index = cell[ok].astype(np.int64) * 64 + votes[ok].astype(np.int64)
    return np.bincount(index, minlength=CELLS * CELLS * 64).reshape(CELLS * CELLS, 64)


def earlier_grid(votes: np.ndarray, main: int, regions: Sequence[Region], totals: np.ndarray) -> EarlierGrid | None:
    """The grid among the regions' that the whole photo carries besides the main one, if any.

    Parameters
    ----------
    votes : ndarray, shape (H, W), int8
        Per-pixel votes (:func:`.votes.vote_map`).
    main : int
        The main grid's code.
    regions : sequence of Region
        Meaningful foreign regions, strongest first.
    totals : ndarray, shape (64,)
        Votes per grid code over the photo; only the ``CANDIDATES`` most
        voted grids besides the main one are tried.

    Returns
    -------
    EarlierGrid or None
        The candidate leading in the most cells, when it leads in at least
        ``MIN_CELL_SHARE`` of them.
    """
    order = [int(g) for g in np.argsort(-totals, kind="stable") if g != main][:CANDIDATES]
    best = None
    for grid in (g for g in order if any(r.grid == g for r in regions)):
        mine = tuple(i for i, r in enumerate(regions) if r.grid == grid)
        everywhere = _cells_led(votes, main, grid, np.ones(votes.shape, dtype=bool))
        keep = np.ones(votes.shape, dtype=bool)
        for i in mine:
            x0, y0, x1, y1 = regions[i].bbox
            keep[max(0, y0 - W): y1 + W + 1, max(0, x0 - W): x1 + W + 1] = False
        outside = _cells_led(votes, main, grid, keep)
        led = max(everywhere, outside)
        if ((everywhere >= MIN_CELL_SHARE_ALL * CELLS * CELLS or outside >= MIN_CELL_SHARE * CELLS * CELLS)
                and (best is None or led > best.cells_led)):
            best = EarlierGrid(grid, led, CELLS * CELLS, mine)
    return best


def _cells_led(votes: np.ndarray, main: int, grid: int, keep: np.ndarray) -> int:
    """Cells where ``grid`` has ``MIN_CELL_VOTES`` votes and ``LEAD`` times those of every other non-main grid."""
    counts = _cell_counts(votes, keep)
    counts[:, main] = 0
    own = counts[:, grid].copy()
    counts[:, grid] = 0
    return int(((own >= MIN_CELL_VOTES) & (own >= LEAD * counts.max(axis=1))).sum())
