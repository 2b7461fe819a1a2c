"""Naming the image's Bayer pattern by demosaicing it again (Bammey et al., 2022).

The phase votes of :mod:`.votes` say which blocks share the image's mosaic,
not which colour the sensor sampled where: that depends on the demosaicing
algorithm (bilinear interpolation leaves the sampled pixels the noisiest,
Hamilton-Adams the smoothest). To name the pattern, small tiles of the blocks
that agree with the image's phase are sampled again through each of the four
Bayer patterns and demosaiced by each reference algorithm of
:mod:`.demosaic`; the pair (algorithm, pattern) that reproduces the tiles
best is retained, and each tile votes for the pattern that reproduces it
best under that algorithm. The name is reported only when the pattern with
the most votes beats the runner-up decisively: ``P(Bin(w + r, 1/2) >= w) <=
1e-6`` for ``w`` and ``r`` votes (a sign test between the two). After JPEG
with chroma subsampling the colour detail that tells the patterns apart is
gone, the votes split, and the name is left undetermined rather than guessed.

The name is only as good as the resemblance of the camera's demosaicing to a
reference one; the region test does not depend on it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .bayer import PATTERNS, mosaic
from .demosaic import ALGORITHMS, demosaic
from .significance import log10_binom_tail

MARGIN = 4
"""Pixels around each tile: the reference algorithms reach 3 pixels away."""

MAX_TILES = 256
NAME_ALPHA = 1e-6


def _gather(rgb: np.ndarray, blocks: np.ndarray, block: int) -> np.ndarray:
    """Tiles of the blocks with a margin, mirrored at the image edge; shape (n, T, T, 3), T = block + 2 MARGIN."""
    h, w = rgb.shape[:2]
    offs = np.arange(-MARGIN, block + MARGIN)
    rows = blocks[:, 0:1] * block + offs
    cols = blocks[:, 1:2] * block + offs
    rows = np.abs(rows)
    rows = np.where(rows >= h, 2 * h - 2 - rows, rows)
    cols = np.abs(cols)
    cols = np.where(cols >= w, 2 * w - 2 - cols, cols)
    return rgb[rows[:, :, None], cols[:, None, :]]


def name_pattern(rgb: np.ndarray, votes, block: int, full_scale: float) -> dict[str, Any]:
    """Name the Bayer pattern of the blocks agreeing with the image's phase.

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3)
        Stored grid (read only), values in ``[0, full_scale]``.
    votes : PhaseVotes
        From :func:`.votes.phase_votes`.
    block : int
        Block side, pixels (even, so tiles keep the image's cell phase).
    full_scale : float

    Returns
    -------
    dict
        ``pattern`` (name or None when not significant), ``algorithm`` (the
        reference demosaicing that reproduces the tiles best), ``tile_votes``
        (per pattern), ``log10_p`` of the winner's votes, ``errors`` (mean
        absolute reproduction error per algorithm and pattern, 8-bit units)
        and ``n_tiles``.
    """
    agree = np.argwhere(votes.shift_vote == 0)
    if len(agree) == 0:
        return {"pattern": None, "algorithm": None, "tile_votes": {}, "log10_p": 0.0, "errors": {}, "n_tiles": 0}
    pick = agree[np.unique(np.linspace(0, len(agree) - 1, min(MAX_TILES, len(agree))).round().astype(int))]
    tiles = _gather(rgb, pick, block).astype(np.float64) * (255.0 / full_scale)
    n, t = tiles.shape[:2]
    # Side by side in one strip: tiles and margins have even sides, so every
    # tile keeps the cell phase it has in the photo.
    strip = tiles.transpose(1, 0, 2, 3).reshape(t, n * t, 3)
    inner = np.zeros((t, n * t), dtype=bool)
    for i in range(n):
        inner[MARGIN:MARGIN + block, i * t + MARGIN: i * t + MARGIN + block] = True
    err = np.empty((len(ALGORITHMS), len(PATTERNS), n))
    for a, algorithm in enumerate(ALGORITHMS):
        for p, pattern in enumerate(PATTERNS):
            diff = np.abs(demosaic(mosaic(strip, pattern), pattern, algorithm) - strip).sum(axis=2)
            err[a, p] = (diff * inner).reshape(t, n, t).sum(axis=(0, 2)) / (3 * block * block)
    mean = err.mean(axis=2)
    a_best = int(np.unravel_index(np.argmin(mean), mean.shape)[0])
    tile_votes = np.bincount(np.argmin(err[a_best], axis=0), minlength=len(PATTERNS))
    runner_up, p_best = np.argsort(tile_votes, kind="stable")[-2:]
    w, r = int(tile_votes[p_best]), int(tile_votes[runner_up])
    log10_p = float(log10_binom_tail(np.array([w]), np.array([w + r]), 0.5)[0])
    return {
        "pattern": PATTERNS[p_best] if log10_p <= np.log10(NAME_ALPHA) else None,
        "candidate": PATTERNS[p_best],
        "algorithm": ALGORITHMS[a_best],
        "tile_votes": {pat: int(c) for pat, c in zip(PATTERNS, tile_votes)},
        "log10_p": round(log10_p, 3),
        "alpha": NAME_ALPHA,
        "errors": {alg: {pat: round(float(mean[a, p]), 4) for p, pat in enumerate(PATTERNS)}
                   for a, alg in enumerate(ALGORITHMS)},
        "n_tiles": int(n),
    }
