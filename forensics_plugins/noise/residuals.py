"""Each block's fine-grain energy against blocks of like grey level and texture in the same photo.

A camera's noise depends on the grey level (photon noise, then the tone
curve) and its processing depends on the content: denoising flattens smooth
areas, sharpening lifts textured ones, and JPEG quantises both. Blocks are
therefore compared only within cells of like grey level (``intensity_bins``
equal-count bins) and, inside each, like coarse texture (``texture_bins``
equal-count bins); within a cell, a block's energy is standardised by the
cell's median and median absolute deviation (robust to the pasted blocks
themselves, which are a minority in every cell).

References
----------
.. [1] S. Lyu, X. Pan, X. Zhang, "Exposing region splicing forgeries with
   blind local noise estimation", International Journal of Computer Vision
   110(2), 2014, pp. 202-221 (noise compared between regions).
.. [2] D. L. Donoho, I. M. Johnstone, "Ideal spatial adaptation by wavelet
   shrinkage", Biometrika 81(3), 1994, pp. 425-455 (the MAD as a scale).
"""

from __future__ import annotations

import numpy as np

from .blocks import BlockFeatures

_MAD_TO_SD = 1.4826


def robust_spread(x: np.ndarray) -> float:
    """1.4826 times the median absolute deviation: the standard deviation for normal data, robust to outliers."""
    return _MAD_TO_SD * float(np.median(np.abs(x - np.median(x))))


def _equal_count_bins(x: np.ndarray, n: int) -> np.ndarray:
    """Bin index 0..n-1 of each value, by the values' own quantiles."""
    return np.digitize(x, np.quantile(x, np.linspace(0.0, 1.0, n + 1)[1:-1]))


def standardised(features: BlockFeatures, intensity_bins: int, texture_bins: int, min_cell_blocks: int,
                 scale_floor: float, z_clip: float) -> tuple[np.ndarray, np.ndarray]:
    """Robust z-score of each valid block's energy within its (grey level, texture) cell.

    Parameters
    ----------
    features : BlockFeatures
        Arrays of shape (h, w).
    intensity_bins, texture_bins : int
        Cells per grey level and, within each, per texture.
    min_cell_blocks : int
        Blocks of smaller cells are left out (no like content to compare).
    scale_floor : float
        Least scale of a cell, in log energy (a cell of blocks whose fine
        coefficients were all quantised to zero has a MAD of 0).
    z_clip : float
        z-scores are clipped to ``[-z_clip, z_clip]`` so that one block
        cannot carry a window.

    Returns
    -------
    z : ndarray of float32, shape (h, w)
        0 where not used.
    used : ndarray of bool, shape (h, w)
    """
    valid = features.valid
    mean, texture, energy = features.mean[valid], features.texture[valid], features.energy[valid]
    cell = _equal_count_bins(mean, intensity_bins) * texture_bins
    for i in range(intensity_bins):
        sel = cell == i * texture_bins
        if sel.any():
            cell[sel] += _equal_count_bins(texture[sel], texture_bins)
    order = np.argsort(cell, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(cell[order]) != 0])
    z = np.zeros(energy.shape, np.float32)
    keep = np.zeros(energy.shape, bool)
    for members in np.split(order, starts[1:]):
        if members.size < min_cell_blocks:
            continue
        e = energy[members]
        scale = max(robust_spread(e), scale_floor)
        z[members] = np.clip((e - np.median(e)) / scale, -z_clip, z_clip)
        keep[members] = True
    out = np.zeros(valid.shape, np.float32)
    used = np.zeros(valid.shape, bool)
    out[valid], used[valid] = z, keep
    return out, used
