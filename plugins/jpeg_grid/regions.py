"""Regions whose pixels vote for a grid other than the main one, each with its NFA.

Votes are tallied per tile of 8x8 pixels. For each candidate grid ``g``:

1. seeds: tiles whose surrounding window (each of ``seed_windows``, tiles
   square: a small one for small dense regions, a large one for large
   sparse ones) holds significantly more votes for ``g`` than the null rate
   ``p_g`` (binomial tail below ``10 ** seed_log10``);
2. growing: the seeds' connected component of tiles whose local vote
   density (``grow_window`` tiles square) exceeds the background density
   (away from the seeds) by ``grow_fraction`` of the seeds' excess over it,
   holes filled;
3. validation, as in ZERO (Nikoukhah et al., CVPRW 2019; IPOL 2021): the region's
   votes for ``g`` against the binomial law of its trials with probability
   ``p_g``, ``NFA = N_tests * P[B(n, p_g) >= k]``.

Votes are not independent: a pixel's vote depends on the 64 blocks around it,
and neighbouring pixels share most of them. One trial is therefore counted
per ``pixels_per_trial`` pixels (both ``n`` and ``k`` are divided by it), a
conservative choice; the default 64 is one trial per 8x8 block.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage, stats

from .nfa import log10_binomial_tail


@dataclass(frozen=True)
class Region:
    """One detected region.

    Attributes
    ----------
    grid : int
        Grid code ``8 * dy + dx`` its pixels vote for.
    tiles : ndarray, shape (Ht, Wt), bool
        Its tiles (``cell`` x ``cell`` pixels each).
    n_pixels : int
        Pixels of the region that could vote.
    votes : int
        Their votes for ``grid``.
    p_null : float
        Probability of a vote for ``grid`` under the null hypothesis.
    log10_nfa : float
        log10 of the number of false alarms.
    """

    grid: int
    tiles: np.ndarray
    n_pixels: int
    votes: int
    p_null: float
    log10_nfa: float


def _box_sum(a: np.ndarray, side: int) -> np.ndarray:
    """Exact sum of the integer array ``a`` over the ``side`` x ``side`` window centred on each entry (``side`` odd).

    Outside the array counts as zero. Integral image in int64, so counts are
    never rounded (a window exactly at the critical count must stay there).
    """
    r = side // 2
    c = np.pad(a.astype(np.int64), ((r + 1, r), (r + 1, r))).cumsum(axis=0).cumsum(axis=1)
    return c[side:, side:] - c[:-side, side:] - c[side:, :-side] + c[:-side, :-side]


class _SeedTest:
    """Which windows hold significantly many votes: the binomial critical count per window size, computed once.

    Parameters
    ----------
    n : ndarray of int
        Trials of each window.
    log10_alpha : float
        A window is a seed when its tail probability is at most ``10 ** log10_alpha``.
    """

    def __init__(self, n: np.ndarray, log10_alpha: float):
        self.levels, inverse = np.unique(n, return_inverse=True)
        self.inverse = inverse.reshape(n.shape)
        self.alpha = 10.0 ** log10_alpha

    def __call__(self, k: np.ndarray, p: float) -> np.ndarray:
        # The smallest k with P[X >= k] <= alpha is isf(alpha) + 1 for a discrete law.
        k_crit = stats.binom.isf(self.alpha, self.levels, p) + 1.0
        k_crit[self.levels == 0] = np.inf
        return k >= k_crit[self.inverse]


def grow_regions(hist: np.ndarray, eligible: np.ndarray, candidates: Iterable[int], p_null: Mapping[int, float],
                 log10_n_tests: float, params: Mapping[str, Any], use_ring: bool = False,
                 references: Mapping[int, tuple[list[int], float]] | None = None) -> list[Region]:
    """Regions of tiles that vote for a candidate grid more than the null allows.

    Parameters
    ----------
    hist : ndarray, shape (Ht, Wt, 64)
        Votes per grid code per tile (:func:`.votes.cell_tally`).
    eligible : ndarray, shape (Ht, Wt)
        Pixels per tile that could vote.
    candidates : iterable of int
        Grid codes to look for.
    p_null : mapping of int to float
        Null probability of a vote for each candidate.
    log10_n_tests : float
        log10 of the number of tests the NFA accounts for.
    params : mapping
        ``seed_windows``, ``grow_window`` (tiles), ``seed_log10``, ``grow_fraction``,
        ``min_region_tiles``, ``pixels_per_trial``, ``ring_tiles``.
    use_ring : bool
        Also take as null rate the density of votes for the grid in a ring of
        ``ring_tiles`` around the region (times the candidate's factor in
        ``references``), when higher: a region must stand out from its own
        surroundings, not only from the whole photo.
    references : mapping of int to (list of int, float), optional
        For each candidate, grids whose vote density inside the region, times
        the factor, is also taken as null rate when higher: grids that the
        photo's content favours about as much as the candidate wherever the
        candidate is favoured by content alone (see
        :func:`mirror_references`).

    Returns
    -------
    list of Region
        Every grown region, meaningful or not, strongest first.
    """
    ppt = int(params["pixels_per_trial"])
    seed_windows = [int(w) for w in params["seed_windows"]]
    grow_w = int(params["grow_window"])
    eligible = eligible.astype(np.int64)
    n_grow = np.maximum(_box_sum(eligible, grow_w), 1)
    seed_tests = [(w, _SeedTest(_box_sum(eligible, w) // ppt, float(params["seed_log10"]))) for w in seed_windows]
    by_grid = np.ascontiguousarray(np.moveaxis(hist, -1, 0))
    ring = np.ones((3, 3), bool)
    found = []
    for g in candidates:
        p = float(p_null[g])
        votes = by_grid[g].astype(np.int64)
        seeds = np.zeros(votes.shape, bool)
        for w, test in seed_tests:
            seeds |= test(_box_sum(votes, w) // ppt, p)
        if not seeds.any():
            continue
        inside = votes[seeds].sum() / max(eligible[seeds].sum(), 1)
        away = ~ndimage.binary_dilation(seeds, iterations=max(seed_windows))
        background = votes[away].sum() / max(eligible[away].sum(), 1) if away.any() else 0.0
        level = background + float(params["grow_fraction"]) * (inside - background)
        member = ndimage.binary_fill_holes(_box_sum(votes, grow_w) / n_grow > level)
        labels, _ = ndimage.label(member)
        for label in np.unique(labels[seeds & member]):
            if label == 0:
                continue
            tiles = labels == label
            if tiles.sum() < int(params["min_region_tiles"]):
                continue
            n = float(eligible[tiles].sum())
            if n == 0:
                continue
            k = float(votes[tiles].sum())
            local = 0.0
            if use_ring:
                around = ndimage.binary_dilation(tiles, ring, iterations=int(params["ring_tiles"])) & ~tiles
                n_ring = float(eligible[around].sum())
                if n_ring > 0:
                    local = float(votes[around].sum()) / n_ring
            grids, factor = (references or {}).get(g, ((), 1.0))
            for h in grids:
                local = max(local, float(by_grid[h][tiles].sum()) / n)
            p_region = min(1.0, max(p, factor * local))
            log10_nfa = log10_n_tests + log10_binomial_tail(n / ppt, k / ppt, p_region)
            found.append(Region(grid=int(g), tiles=tiles, n_pixels=int(n), votes=int(k), p_null=p_region,
                                log10_nfa=log10_nfa if math.isfinite(log10_nfa) else -1000.0))
    return sorted(found, key=lambda r: r.log10_nfa)


def mirror_references(main: int, axis_factor: float) -> dict[int, tuple[list[int], float]]:
    """For each grid, its mirror images about the main grid (or its nearest grids) and the tolerance on them.

    With the main grid excluded from the vote, a grid sharing a row or
    column phase with it (and the main grid's neighbours above all) collects
    votes wherever the content is smooth along one direction: those votes are
    content, not a pasted grid. Block statistics do not change when the image
    is flipped, so content favours ``(mx + dx, my + dy)`` and its mirror
    images ``(mx - dx, my + dy)``, ``(mx + dx, my - dy)``, ``(mx - dx, my - dy)``
    alike, whereas a pasted grid raises only itself. A grid that is its own
    mirror image (``dx, dy`` in {0, 4}) is compared with its four nearest grids
    and with its transpose ``(mx + dy, my + dx)``: content that favours the
    half-block shift ``(4, 0)`` favours its neighbours or, in isotropic
    texture, ``(0, 4)`` too.

    "Alike" holds only roughly for the grids sharing a phase with the main
    grid: on large smooth areas content was measured to favour one up to 1.35
    times more than its mirror image. Their reference rates are multiplied by
    ``axis_factor``; the other grids, which content hardly favours at all
    (a few votes per thousand pixels), keep a factor of 1.

    Parameters
    ----------
    main : int
        Code of the main grid.
    axis_factor : float
        Tolerance applied to the reference rates of grids sharing a row or
        column phase with the main grid.

    Returns
    -------
    dict of int to (list of int, float)
        For each of the 63 other codes, its reference grid codes and factor.
    """
    mx, my = main % 8, main // 8
    out = {}
    for g in range(64):
        if g == main:
            continue
        dx, dy = (g % 8 - mx) % 8, (g // 8 - my) % 8
        images = {((mx + sx * dx) % 8) + 8 * ((my + sy * dy) % 8) for sx in (1, -1) for sy in (1, -1)} - {g}
        if not images:
            images = {((g % 8 + ex) % 8) + 8 * ((g // 8 + ey) % 8) for ex, ey in ((1, 0), (-1, 0), (0, 1), (0, -1))}
            images.add(((mx + dy) % 8) + 8 * ((my + dx) % 8))
        out[g] = (sorted(images - {main}), axis_factor if 0 in (dx, dy) else 1.0)
    return out
