"""Regions of pixels voting for one grid, grown as in ZERO, with their NFA.

ZERO (Nikoukhah et al., CVPRW 2019; IPOL 2021) grows a region from a
pixel voting for grid ``g`` by adding every pixel that votes ``g`` and lies
within Chebyshev distance ``W = 9`` of a pixel already in it. A region is
therefore exactly a connected component of the pixels voting ``g`` under the
adjacency ``|dx| <= W and |dy| <= W``, which this module computes with a
union-find over cells of ``W + 1`` pixels a side.

A meaningful region must hold at least one vote per 8x8 block on average, so
its votes are rarely more than 8 pixels apart; ``W = 9`` allows some slack.
Its NFA is ``N_T * P[B(n, 1/64) >= k]`` with ``n`` its bounding box's area
and ``k`` its pixels, both divided by 64 (neighbouring votes share most of
their blocks, one vote per block is a rough count of the independent ones).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from .nfa import log10_binomial_tail

W = 9
P_VOTE = 1.0 / 64.0


@dataclass(frozen=True)
class Region:
    """One grown region.

    Attributes
    ----------
    label : int
        Its value in the label map of :func:`components`.
    grid : int
        Grid code ``8 * dy + dx`` its pixels vote for.
    n_pixels : int
        Its pixels (all voting ``grid``).
    bbox : tuple of int
        ``(x0, y0, x1, y1)``, inclusive pixel bounds.
    log10_nfa : float
        log10 of the number of false alarms.
    """

    label: int
    grid: int
    n_pixels: int
    bbox: tuple[int, int, int, int]
    log10_nfa: float


@nb.njit(cache=True, inline="always")
def _find(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@nb.njit(cache=True, inline="always")
def _union(parent, a, b):
    ra = _find(parent, a)
    rb = _find(parent, b)
    if ra < rb:
        parent[rb] = ra
    elif rb < ra:
        parent[ra] = rb


@nb.njit(cache=True)
def _near(py, px, a0, a1, b0, b1, reach):
    """Whether some pixel of ``a0:a1`` lies within ``reach`` (Chebyshev) of some pixel of ``b0:b1``."""
    for i in range(a0, a1):
        for j in range(b0, b1):
            if abs(py[i] - py[j]) <= reach and abs(px[i] - px[j]) <= reach:
                return True
    return False


@nb.njit(cache=True)
def _components(votes, member, reach):
    h, w = votes.shape
    # Cells of side reach + 1: two pixels of one grid in one cell are always adjacent, and a pixel's
    # neighbours lie in its own cell or the 8 around it.
    side = reach + 1
    ch, cw = (h + side - 1) // side, (w + side - 1) // side
    slot = np.full(64, -1, np.int64)
    m = 0
    for g in range(64):
        if member[g]:
            slot[g] = m
            m += 1
    # Member pixels bucketed by (grid, cell), a counting sort.
    start = np.zeros(m * ch * cw + 1, np.int32)
    for y in range(h):
        for x in range(w):
            g = votes[y, x]
            if g >= 0 and slot[g] >= 0:
                start[(slot[g] * ch + y // side) * cw + x // side + 1] += 1
    for b in range(m * ch * cw):
        start[b + 1] += start[b]
    n = start[m * ch * cw]
    fill = start[:-1].copy()
    py = np.empty(n, np.int32)
    px = np.empty(n, np.int32)
    for y in range(h):
        for x in range(w):
            g = votes[y, x]
            if g >= 0 and slot[g] >= 0:
                b = (slot[g] * ch + y // side) * cw + x // side
                py[fill[b]] = y
                px[fill[b]] = x
                fill[b] += 1
    parent = np.empty(n, np.int32)
    for b in range(m * ch * cw):
        for k in range(start[b], start[b + 1]):
            parent[k] = start[b]
    for j in range(m):
        for cy in range(ch):
            for cx in range(cw):
                b = (j * ch + cy) * cw + cx
                if start[b] == start[b + 1]:
                    continue
                for ey, ex in ((0, 1), (1, -1), (1, 0), (1, 1)):
                    ny, nx = cy + ey, cx + ex
                    if ny >= ch or nx < 0 or nx >= cw:
                        continue
                    nb_ = (j * ch + ny) * cw + nx
                    if start[nb_] == start[nb_ + 1]:
                        continue
                    if _find(parent, start[b]) == _find(parent, start[nb_]):
                        continue
                    if _near(py, px, start[b], start[b + 1], start[nb_], start[nb_ + 1], reach):
                        _union(parent, start[b], start[nb_])
    labels = np.full((h, w), -1, np.int32)
    root_label = np.full(n, -1, np.int32)
    count = 0
    for k in range(n):
        root = _find(parent, k)
        if root_label[root] < 0:
            root_label[root] = count
            count += 1
    size = np.zeros(count, np.int64)
    grid = np.zeros(count, np.int8)
    bbox = np.empty((count, 4), np.int32)
    bbox[:, 0] = w
    bbox[:, 1] = h
    bbox[:, 2] = -1
    bbox[:, 3] = -1
    for k in range(n):
        c = root_label[_find(parent, k)]
        y, x = py[k], px[k]
        labels[y, x] = c
        size[c] += 1
        grid[c] = votes[y, x]
        bbox[c, 0] = min(bbox[c, 0], x)
        bbox[c, 1] = min(bbox[c, 1], y)
        bbox[c, 2] = max(bbox[c, 2], x)
        bbox[c, 3] = max(bbox[c, 3], y)
    return labels, size, grid, bbox


def components(votes: np.ndarray, grids: np.ndarray,
               reach: int = W) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Connected components of the pixels voting for one of ``grids``, pixels of one grid at a time.

    Parameters
    ----------
    votes : ndarray, shape (H, W), int8
        Vote map (:func:`.votes.vote_map`), negative where no vote.
    grids : ndarray, shape (64,), bool
        Grid codes taking part.
    reach : int
        Two pixels voting the same grid are adjacent when ``|dx| <= reach``
        and ``|dy| <= reach``.

    Returns
    -------
    labels : ndarray, shape (H, W), int32
        Component index, -1 for pixels not taking part.
    size : ndarray, shape (K,), int64
        Pixels per component.
    grid : ndarray, shape (K,), int8
        The grid each component votes for.
    bbox : ndarray, shape (K, 4), int32
        ``x0, y0, x1, y1`` per component, inclusive.
    """
    return _components(np.ascontiguousarray(votes, dtype=np.int8), np.ascontiguousarray(grids, dtype=bool),
                       int(reach))


def log10_n_tests(shape: tuple[int, int]) -> float:
    """ZERO's number of tests, log10: 64 grids squared times the image size squared, ``(64 X Y)^2``."""
    return 2.0 * math.log10(64.0) + 2.0 * math.log10(shape[1]) + 2.0 * math.log10(shape[0])


def min_region_pixels(log_nt: float) -> int:
    """Smallest region that can be meaningful (ZERO's ``ceil(64 log_nt / log10 64)`` pixels).

    ``k / 64`` successes at probability 1/64 have a tail of at least
    ``64 ** -(k / 64)``, so a smaller region cannot bring the NFA below 1.
    """
    return math.ceil(64.0 * log_nt / math.log10(64.0))


def find_regions(votes: np.ndarray, grids: np.ndarray, log_nt: float) -> tuple[np.ndarray, list[Region]]:
    """Regions voting for one of ``grids``, large enough to be meaningful, strongest first.

    Parameters
    ----------
    votes : ndarray, shape (H, W), int8
        Vote map.
    grids : ndarray, shape (64,), bool
        Grid codes searched.
    log_nt : float
        log10 of the number of tests (:func:`log10_n_tests`).

    Returns
    -------
    labels : ndarray, shape (H, W), int32
        Component map from :func:`components`.
    regions : list of Region
        Components of at least :func:`min_region_pixels` pixels, meaningful or
        not, by increasing NFA.

    References
    ----------
    T. Nikoukhah, J. Anger, M. Colom, J.-M. Morel, R. Grompone von Gioi, ZERO: a Local JPEG Grid Origin Detector
    Based on the Number of DCT Zeros and its Applications in Image Forensics, IPOL 11 (2021), pp. 396-433.
    """
    labels, size, grid, bbox = components(votes, grids)
    found = []
    for k in np.flatnonzero(size >= min_region_pixels(log_nt)):
        x0, y0, x1, y1 = (int(v) for v in bbox[k])
        n = (x1 - x0 + 1) * (y1 - y0 + 1) // 64
        log10_nfa = log_nt + log10_binomial_tail(n, int(size[k]) // 64, P_VOTE)
        found.append(Region(label=int(k), grid=int(grid[k]), n_pixels=int(size[k]), bbox=(x0, y0, x1, y1),
                            log10_nfa=log10_nfa if math.isfinite(log10_nfa) else -1000.0))
    return labels, sorted(found, key=lambda r: r.log10_nfa)
