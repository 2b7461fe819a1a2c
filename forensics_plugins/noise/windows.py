"""Windows whose blocks are noisier or smoother than the photo's own windows are.

A window's statistic is the mean z-score of its used blocks
(:func:`.residuals.standardised`). Real photos' noise varies from place to
place far more than independent blocks would: in-camera denoising and
sharpening adapt to the content, and JPEG quantises smooth areas to silence.
On the shared authentic photos a test that took blocks as independent reached
z of 20 to 110. So a window is measured against the photo's own windows of
the same size instead: its deviation is its distance from their median in
units of their robust spread (1.4826 times the median absolute deviation), or
of the spread a mean of independent unit z-scores would have (``1 / size``)
when that is larger: a photo whose noise is the same everywhere (rare in
real photos, usual in synthetic ones) must not make every window's wobble
look large.
That deviation is a measurement, not a p-value; the detector's strength is
the likelihood ratio calibrated on real photos.

References
----------
.. [1] M. Gardella, P. Musé, J.-M. Morel, M. Colom, "Noisesniffer: a fully
   automatic image forgery detector based on noise analysis", IEEE
   International Workshop on Biometrics and Forensics, 2021 (windows of
   blocks against the photo's own noise statistics).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from forensics_core import box_sums

from .residuals import robust_spread


@dataclass(frozen=True)
class Window:
    """One measured window, in blocks.

    Attributes
    ----------
    row, col, size : int
        Top-left block and side, in blocks.
    n : int
        Used blocks in the window.
    mean_z : float
        Mean z-score of those blocks (positive: noisier than like content).
    deviation : float
        ``(mean_z - median) / spread`` over the photo's windows of this size.
    """

    row: int
    col: int
    size: int
    n: int
    mean_z: float
    deviation: float


def scan(z: np.ndarray, used: np.ndarray, fractions: tuple[int, ...], min_size: int,
         min_used_share: float) -> tuple[list[Window], dict[int, float]]:
    """Every window of each size (stride half a side) with its deviation.

    Parameters
    ----------
    z : ndarray, shape (h, w)
        Block z-scores (0 where not used).
    used : ndarray of bool, shape (h, w)
    fractions : tuple of int
        Window sides as fractions of the shorter side: ``min(h, w) // f`` blocks.
    min_size : int
        Least side, in blocks.
    min_used_share : float
        Windows with a smaller share of used blocks are not measured.

    Returns
    -------
    windows : list of Window, largest absolute deviation first
    spreads : dict
        Window side (blocks) -> the robust spread of its windows' means.
    """
    out: list[Window] = []
    spreads: dict[int, float] = {}
    for f in fractions:
        size = max(min_size, min(z.shape) // f)
        if size > min(z.shape) or size in spreads:
            continue
        step = max(size // 2, 1)
        n = box_sums(used.astype(np.float64), size, step)
        total = box_sums(z.astype(np.float64), size, step)
        ok = n >= min_used_share * size * size
        if ok.sum() < 5:
            continue
        means = total[ok] / n[ok]
        centre = float(np.median(means))
        spread = max(robust_spread(means), 1.0 / size)
        spreads[size] = round(spread, 4)
        rows, cols = np.nonzero(ok)
        dev = (means - centre) / spread
        out.extend(Window(int(r) * step, int(c) * step, size, int(k), round(float(m), 4), round(float(d), 3))
                   for r, c, k, m, d in zip(rows, cols, n[ok], means, dev))
    out.sort(key=lambda w: (-abs(w.deviation), w.size, w.row, w.col))
    return out, spreads


def distinct(windows: list[Window], threshold: float, limit: int) -> list[Window]:
    """The windows with ``|deviation| >= threshold``, best first, none centred inside one listed before."""
    listed: list[Window] = []
    for w in windows:
        if abs(w.deviation) < threshold or len(listed) >= limit:
            break
        cy, cx = w.row + w.size / 2, w.col + w.size / 2
        if not any(o.row <= cy < o.row + o.size and o.col <= cx < o.col + o.size for o in listed):
            listed.append(w)
    return listed
