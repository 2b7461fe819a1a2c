"""Stage 3: a-contrario detection of regions whose mosaic phase disagrees with the image's.

Each usable block answers a binary question (:mod:`.votes`): does its green
lie on the image's diagonal; and, among the blocks where it does, are red and
blue where the image has them. Under the null hypothesis H0 "this region was
demosaiced with the image's pattern, in its phase", block ``i`` disagrees
with probability at most ``q_i``, independently of the others: ``q_i = 1/2``
when it carries no trace at all, and on real photos the content-matched rate
of :mod:`.content_null` (blocks of the same colour vote alike wherever they
are). For a window of blocks with ``n`` votes of which ``k`` disagree, the
disagreement count is a sum of independent Bernoulli variables of mean at
most ``qbar``, the mean of ``q_i`` over the window, and its tail is bounded by
the binomial one (Hoeffding, 1956, th. 4), so the number of false alarms is
(Desolneux, Moisan & Morel, 2008, ch. 4; Bammey et al., 2022)

.. math::  \\mathrm{NFA} = N_{\\text{tests}} \\, \\max\\left(
           P\\left(\\mathrm{Bin}(n, \\bar q) \\ge k\\right),
           P\\left(\\mathrm{Bin}(n_r, 1/2) \\ge n_r - k_r\\right)\\right),

where ``N_tests`` counts every window of both questions and ``n_r``,
``k_r`` are the votes and the disagreeing votes in the window's ring (the
window grown by its own height and width on every side, less the window).
The second term asks that the photo's own phase be shown around the window
at least as clearly as the window departs from it. A pasted piece of another
mosaic phase is a contrast between two phases. On real photos the rate at
which blocks vote against the phase shifts by area of content, through
sharpening, denoising, colour processing and chroma subsampling on the
Bayer cell: measured on camera JPEGs, whole areas (foliage and gravel, a
road, a mortar joint) voted against at rates of 0.6 to 0.94 over hundreds of
blocks, while after removing a local mean neighbouring blocks' votes
correlated by less than 0.05. The dependence is thus an area-level shift of
the rate, which deflating the number of trials by a short-range design
effect would not remove; where the photo's phase is not even significant
around a window, the window's disagreement is read as such a shift, not as
another mosaic. Requiring both events keeps ``NFA <= eps`` an event of probability at most
``eps / N_tests`` per window under H0, so the expected number of false
windows stays at most ``eps``.

Windows are axis-aligned rectangles of blocks whose sides take the values
2, 3, 4, 6, 8, 11, 16, ... (about sqrt(2) apart) with aspect ratio at most 4,
placed at every quarter of their side. A region is a connected set of blocks
lying in significant windows that disagree with the image themselves or in
the majority of their 3 x 3 neighbourhood; its NFA is the smallest NFA of the significant
windows whose disagreeing votes lie mostly inside it (a region without such a
window is dropped).

References
----------
W. Hoeffding, On the distribution of the number of successes in independent
trials, Annals of Mathematical Statistics 27(3), 713-721, 1956.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from forensics_core import integral_image

from .significance import log10_binom_tail, log10_chernoff

KINDS = ("diagonal", "red_blue")
"""``diagonal``: green on the other diagonal (shift by one pixel in x or y);
``red_blue``: red and blue swapped (shift by one pixel in both)."""

MAX_ASPECT = 4


@dataclass(frozen=True)
class Question:
    """One binary question asked of every block.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    disagree : ndarray of bool, shape (ny, nx)
        Blocks answering against the image.
    voting : ndarray of bool, shape (ny, nx)
        Blocks that answer at all.
    null : ndarray of float, shape (ny, nx), optional
        Each block's largest probability of disagreeing under H0, in
        ``[1/2, 1)``; 1/2 everywhere when None.
    """

    kind: str
    disagree: np.ndarray
    voting: np.ndarray
    null: np.ndarray | None = None


@dataclass(frozen=True)
class Region:
    """A detected region.

    Attributes
    ----------
    kind : str
    blocks : ndarray of bool, shape (ny, nx)
    log10_nfa : float
    window : tuple of int
        ``(y0, x0, h, w)`` in blocks, of the most significant window.
    votes_against, votes : int
        Disagreeing and voting blocks inside the region (descriptive: the
        region was selected by these votes, so they are not a test).
    null_rate : float
        ``qbar`` of the most significant window.
    ring_agree, ring_votes : int
        Agreeing and voting blocks in that window's ring.
    """

    kind: str
    blocks: np.ndarray
    log10_nfa: float
    window: tuple[int, int, int, int]
    votes_against: int
    votes: int
    null_rate: float = 0.5
    ring_agree: int = 0
    ring_votes: int = 0


@dataclass(frozen=True)
class Scan:
    """Outcome of the window scan.

    Attributes
    ----------
    n_tests : int
        Windows tested over both questions.
    regions : list of Region
        Most significant first.
    min_log10_nfa : float
        Smallest log10 NFA of any window (at least the Chernoff bound
        when no window came near significance).
    """

    n_tests: int
    regions: list[Region]
    min_log10_nfa: float


def window_sides(n: int) -> list[int]:
    """Window sides in blocks, from 2 to ``n``, about sqrt(2) apart."""
    sides = []
    s = 2.0
    while round(s) <= n:
        if not sides or round(s) != sides[-1]:
            sides.append(round(s))
        s *= np.sqrt(2.0)
    return sides


def _shapes(ny: int, nx: int) -> list[tuple[int, int, int, int]]:
    """Tested window shapes ``(h, w, stride_y, stride_x)``."""
    out = []
    for h in window_sides(ny):
        for w in window_sides(nx):
            if max(h, w) <= MAX_ASPECT * min(h, w):
                out.append((h, w, max(1, h // 4), max(1, w // 4)))
    return out


def count_tests(ny: int, nx: int) -> int:
    """Number of windows of one question on a grid of ``ny`` x ``nx`` blocks."""
    return sum(len(range(0, ny - h + 1, sy)) * len(range(0, nx - w + 1, sx)) for h, w, sy, sx in _shapes(ny, nx))


def _window_counts(ii: np.ndarray, ys: np.ndarray, xs: np.ndarray, h: int, w: int) -> np.ndarray:
    return (ii[np.ix_(ys + h, xs + w)] - ii[np.ix_(ys, xs + w)]
            - ii[np.ix_(ys + h, xs)] + ii[np.ix_(ys, xs)])


def _window_sums(ii: np.ndarray, win: np.ndarray) -> np.ndarray:
    """Sums over windows ``(y0, x0, h, w)`` (rows of ``win``) from an integral image."""
    y0, x0, h, w = win.T
    return ii[y0 + h, x0 + w] - ii[y0, x0 + w] - ii[y0 + h, x0] + ii[y0, x0]


def _significant_windows(q: Question, log10_tests: float, log10_eps: float):
    """Windows of one question with NFA <= eps, and the smallest log10 NFA seen.

    Returns
    -------
    log10_nfa : ndarray, shape (m,)
    windows : ndarray of int, shape (m, 4)
        ``(y0, x0, h, w)`` in blocks.
    null_rate : ndarray, shape (m,)
        ``qbar`` of each window.
    ring : ndarray of int, shape (m, 2)
        Agreeing and voting blocks in each window's ring.
    best : float
    """
    ny, nx = q.disagree.shape
    ik = integral_image(q.disagree & q.voting)
    iv = integral_image(q.voting)
    null = np.full((ny, nx), 0.5) if q.null is None else q.null
    iq = integral_image(np.where(q.voting, null, 0.0))
    found: list[tuple[np.ndarray, ...]] = []
    best = 0.0
    for h, w, sy, sx in _shapes(ny, nx):
        ys = np.arange(0, ny - h + 1, sy)
        xs = np.arange(0, nx - w + 1, sx)
        k = _window_counts(ik, ys, xs, h, w)
        n = _window_counts(iv, ys, xs, h, w)
        # The Chernoff bound exceeds the exact tail by at most a factor
        # sqrt(8 n), and the tail grows with the null rate (at least 1/2):
        # only windows the bound at 1/2 cannot rule out get the exact test.
        bound = log10_chernoff(k, n, 0.5) + log10_tests
        cand = bound - 0.5 * np.log10(8.0 * np.maximum(n, 1)) <= max(log10_eps, best)
        if not cand.any():
            best = min(best, float(bound.min()))
            continue
        iy, ix = np.nonzero(cand)
        y0, x0 = ys[iy], xs[ix]
        kc, nc = k[iy, ix], n[iy, ix]
        win = np.stack([y0, x0, np.full(len(iy), h), np.full(len(iy), w)], axis=1)
        qbar = np.clip(_window_sums(iq, win) / np.maximum(nc, 1), 0.5, 1.0 - 1e-9)
        ry0, rx0 = np.maximum(y0 - h, 0), np.maximum(x0 - w, 0)
        grown = np.stack([ry0, rx0, np.minimum(y0 + 2 * h, ny) - ry0, np.minimum(x0 + 2 * w, nx) - rx0], axis=1)
        ring_n = _window_sums(iv, grown) - nc
        ring_k = _window_sums(ik, grown) - kc
        nfa = np.maximum(log10_binom_tail(kc, nc, qbar),
                         log10_binom_tail(ring_n - ring_k, ring_n, 0.5)) + log10_tests
        best = min(best, float(nfa.min()))
        keep = nfa <= log10_eps
        found.append((nfa[keep], win[keep], qbar[keep], np.stack([ring_n - ring_k, ring_n], axis=1)[keep]))
    if not found:
        return np.empty(0), np.empty((0, 4), dtype=int), np.empty(0), np.empty((0, 2), dtype=int), best
    nfas, wins, qbars, rings = (np.concatenate(part) for part in zip(*found))
    return nfas, wins.astype(int), qbars, rings.astype(int), best


def _union(win: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Blocks covered by any of the windows ``(y0, x0, h, w)``, by summing their corner differences."""
    diff = np.zeros((shape[0] + 1, shape[1] + 1), dtype=np.int64)
    y0, x0, h, w = win.T
    np.add.at(diff, (y0, x0), 1)
    np.add.at(diff, (y0 + h, x0), -1)
    np.add.at(diff, (y0, x0 + w), -1)
    np.add.at(diff, (y0 + h, x0 + w), 1)
    return diff.cumsum(axis=0).cumsum(axis=1)[: shape[0], : shape[1]] > 0


def _local_majority(q: Question) -> np.ndarray:
    """Blocks where most votes of the 3 x 3 neighbourhood disagree (none where nothing votes)."""
    box = np.ones((3, 3), dtype=np.int32)
    against = ndimage.correlate((q.disagree & q.voting).astype(np.int32), box, mode="constant")
    votes = ndimage.correlate(q.voting.astype(np.int32), box, mode="constant")
    return 2 * against > votes


def scan(questions: list[Question], nfa_threshold: float) -> Scan:
    """Find the regions that disagree with the image, for every question.

    Parameters
    ----------
    questions : list of Question
        All on the same block grid.
    nfa_threshold : float
        ``eps``: windows with NFA <= eps are significant.

    Returns
    -------
    Scan
    """
    ny, nx = questions[0].disagree.shape
    n_tests = len(questions) * count_tests(ny, nx)
    log10_tests = float(np.log10(max(n_tests, 1)))
    log10_eps = float(np.log10(nfa_threshold))
    regions: list[Region] = []
    best = 0.0
    for q in questions:
        nfas, win, qbars, rings, q_best = _significant_windows(q, log10_tests, log10_eps)
        best = min(best, q_best)
        if not len(nfas):
            continue
        against = q.disagree & q.voting
        k_all = _window_sums(integral_image(against), win)
        cover = _union(win, (ny, nx))
        labels, count = ndimage.label(cover & (against | _local_majority(q)), structure=np.ones((3, 3), dtype=bool))
        # A significant window holds at least log2(N_tests / eps) disagreeing
        # votes (all n votes against has probability 2^-n), so a component
        # with fewer than half of that cannot own one.
        sizes = ndimage.sum_labels(against, labels, np.arange(1, count + 1))
        k_min = (log10_tests - log10_eps) / np.log10(2.0)
        for lab in np.nonzero(2 * sizes >= k_min)[0] + 1:
            # Blocks that abstain or agree by chance inside a region belong to it.
            blocks = ndimage.binary_fill_holes(labels == lab)
            # A region is supported by the windows whose disagreeing votes lie
            # mostly inside it, not by a window that owes its significance to
            # a neighbouring region.
            own = 2 * _window_sums(integral_image(blocks & against), win) >= k_all
            if not own.any():
                continue
            j = int(np.argmin(np.where(own, nfas, np.inf)))
            regions.append(Region(
                kind=q.kind, blocks=blocks, log10_nfa=float(nfas[j]), window=tuple(int(v) for v in win[j]),
                votes_against=int((blocks & against).sum()), votes=int((blocks & q.voting).sum()),
                null_rate=float(qbars[j]), ring_agree=int(rings[j, 0]), ring_votes=int(rings[j, 1]),
            ))
    regions.sort(key=lambda r: r.log10_nfa)
    return Scan(n_tests=n_tests, regions=regions, min_log10_nfa=best)


def detectable_side(n_blocks: tuple[int, int], agreement: float, vote_rate: float, n_tests: int,
                    nfa_threshold: float) -> int | None:
    """Side, in blocks, of the smallest square region a scan would flag, on average.

    A region with another phase makes a fraction ``agreement`` of its voting
    blocks disagree (the rate at which blocks of this image agree with its
    own phase); ``vote_rate`` of its blocks vote.

    Returns
    -------
    int or None
        None when even the whole grid would not be flagged.
    """
    ny, nx = n_blocks
    log10_limit = np.log10(nfa_threshold) - np.log10(max(n_tests, 1))
    for side in window_sides(min(ny, nx)):
        n = round(vote_rate * side * side)
        k = round(agreement * n)
        if n and log10_binom_tail(np.array([k]), np.array([n]), 0.5)[0] <= log10_limit:
            return side
    return None
