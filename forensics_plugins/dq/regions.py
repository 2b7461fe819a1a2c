"""Windows of blocks that vote "single compression" more often than the rest of the photo.

A window of ``n`` informative blocks with ``k`` "single" votes is compared
with the photo's own stratified rate ``p`` (:func:`.votes.null_rates`). Real
photos vary from place to place more than independent votes would (content,
local processing before the last save), so the count is modelled as
beta-binomial with an intra-class correlation ``rho`` measured on the photo
itself: the robust spread (MAD) of the standardised counts of 4 x 4-block
tiles. The number of false alarms of a window is the count of windows tested
times its tail probability (Desolneux, Moisan & Morel).

References
----------
.. [1] A. Desolneux, L. Moisan, J.-M. Morel, From Gestalt Theory to Image
   Analysis, Springer, 2008 (the NFA).
.. [2] T. Bianchi, A. Piva, "Image forgery localization via block-grained
   analysis of JPEG artifacts", IEEE Trans. Information Forensics and
   Security 7(3), 2012, pp. 1003-1017.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import betaln, logsumexp

TILE = 4
RHO_FLOOR = 1e-4


@dataclass(frozen=True)
class Window:
    """One tested window, in blocks.

    Attributes
    ----------
    row, col, size : int
        Top-left block and side, in blocks.
    n, k : int
        Informative blocks and "single" votes among them.
    expected : float
        The photo's rate of "single" votes for blocks like these.
    log10_nfa : float
        log10 of (windows tested x tail probability).
    """

    row: int
    col: int
    size: int
    n: int
    k: int
    expected: float
    log10_nfa: float


def overdispersion(informative: np.ndarray, single: np.ndarray, rates: np.ndarray) -> float:
    """Intra-class correlation of the votes, from the spread of tile counts, dimensionless."""
    h, w = (informative.shape[0] // TILE) * TILE, (informative.shape[1] // TILE) * TILE

    def tiles(a: np.ndarray) -> np.ndarray:
        return a[:h, :w].reshape(h // TILE, TILE, w // TILE, TILE).sum(axis=(1, 3)).ravel()

    n, k, e = tiles(informative.astype(float)), tiles(single.astype(float)), tiles(np.where(informative, rates, 0.0))
    keep = n >= TILE * TILE / 2
    if keep.sum() < 10:
        return 0.1
    p = np.clip(e[keep] / n[keep], 1e-3, 1 - 1e-3)
    z = (k[keep] - n[keep] * p) / np.sqrt(n[keep] * p * (1 - p))
    spread = 1.4826 * np.median(np.abs(z - np.median(z)))
    return float(max((spread ** 2 - 1.0) / (n[keep].mean() - 1.0), RHO_FLOOR))


def _log10_tail(k: int, n: int, p: float, rho: float) -> float:
    a, b = p * (1.0 / rho - 1.0), (1.0 - p) * (1.0 / rho - 1.0)
    j = np.arange(k, n + 1)
    # The beta-binomial log pmf as scipy.stats.betabinom computes it, from scipy.special alone: importing
    # scipy.stats would add 0.4 s to every run.
    logpmf = -np.log(n + 1.0) - betaln(n - j + 1.0, j + 1.0) + betaln(j + a, n - j + b) - betaln(a, b)
    return float(logsumexp(logpmf) / np.log(10.0))


def scan(informative: np.ndarray, single: np.ndarray, rates: np.ndarray, rho: float,
         sizes: tuple[int, ...], min_informative: int) -> tuple[list[Window], int]:
    """Every window of the given sides (stride half a side) with its NFA; and how many were tested.

    Parameters
    ----------
    informative, single : ndarray of bool, shape (h, w)
    rates : ndarray, shape (h, w)
        :func:`.votes.null_rates`.
    rho : float
        :func:`overdispersion`.
    sizes : tuple of int
        Window sides in blocks.
    min_informative : int
        Windows with fewer informative blocks are counted as tested but not scored.

    Returns
    -------
    windows : list of Window, best first
    n_tests : int
    """
    h, w = informative.shape
    found: list[tuple[int, int, int, int, int, float, float]] = []
    n_tests = 0
    for size in sizes:
        if size > min(h, w):
            continue
        step = max(size // 2, 1)
        for r in range(0, h - size + 1, step):
            for c in range(0, w - size + 1, step):
                n_tests += 1
                inf = informative[r:r + size, c:c + size]
                n = int(inf.sum())
                if n < min_informative:
                    continue
                k = int(single[r:r + size, c:c + size][inf].sum())
                p = float(np.clip(rates[r:r + size, c:c + size][inf].mean(), 1e-3, 1 - 1e-3))
                if k <= n * p:
                    continue
                found.append((r, c, size, n, k, p, _log10_tail(k, n, p, rho)))
    log_tests = np.log10(max(n_tests, 1))
    windows = sorted((Window(r, c, s, n, k, round(p, 4), round(t + log_tests, 3)) for r, c, s, n, k, p, t in found),
                     key=lambda x: x.log10_nfa)
    return windows, n_tests
