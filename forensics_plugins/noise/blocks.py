"""Per 8 x 8 block: mean grey level, coarse texture and fine-grain energy, from the block's DCT.

Noise is white, so it spreads its energy over every DCT frequency of a block,
while the content of most blocks is concentrated at the lowest ones. The
energy at the highest frequencies (``u + v >= fine_min_order``) is therefore
read as the block's noise level, and the energy at the lowest
(``1 <= u + v <= coarse_max_order``), less the noise's own share of it
(white noise puts the fine mean square into every coefficient), as its
texture, which raises the fine energy too and is compared like with like in
:mod:`.residuals`. Without that correction a noisier pasted block would be
sorted with textured blocks of the host and its excess noise hidden.

References
----------
.. [1] B. Mahdian, S. Saic, "Using noise inconsistencies for blind image
   forensics", Image and Vision Computing 27(10), 2009, pp. 1497-1503.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.fft import dctn

BLOCK = 8
_ROWS_PER_BAND = 64


@dataclass(frozen=True)
class BlockFeatures:
    """The block measurements of one photo; every array has shape (h, w), h = H // 8, w = W // 8.

    Attributes
    ----------
    mean : ndarray of float32
        Mean grey level, 0-255.
    texture : ndarray of float32
        ``log(1 + max(E_coarse - n_coarse * E_fine, 0))``, E_coarse the
        summed squared DCT coefficients of the ``n_coarse`` frequencies of
        orders 1 to ``coarse_max_order`` (grey levels squared).
    energy : ndarray of float32
        ``log(energy_floor + E_fine)``, E_fine the mean squared DCT
        coefficient of orders ``fine_min_order`` and above (grey levels
        squared: the block's noise variance for white noise).
    valid : ndarray of bool
        No pixel at or beyond the clipping levels (clipped blocks lost their
        noise).
    """

    mean: np.ndarray
    texture: np.ndarray
    energy: np.ndarray
    valid: np.ndarray


def measure(luma: np.ndarray, fine_min_order: int, coarse_max_order: int, energy_floor: float,
            clip_levels: tuple[float, float]) -> BlockFeatures:
    """Block features of a photo's luma.

    Parameters
    ----------
    luma : ndarray, shape (H, W)
        In [0, 1]. The last H % 8 rows and W % 8 columns are not used.
    fine_min_order, coarse_max_order : int
        Frequency orders ``u + v`` (0-14) of the fine and coarse bands.
    energy_floor : float
        Added to the fine energy before the logarithm (grey levels squared),
        so that a block with no fine energy at all (a flat area of a
        lossless file) has a finite value; decoded JPEG blocks keep the
        rounding noise of 8-bit pixels, about 1/12.
    clip_levels : (float, float)
        A block with a pixel at or below the first or at or above the second
        (grey levels) is not valid.

    Returns
    -------
    BlockFeatures
    """
    h, w = luma.shape[0] // BLOCK, luma.shape[1] // BLOCK
    u, v = np.meshgrid(np.arange(BLOCK), np.arange(BLOCK), indexing="ij")
    order = (u + v).ravel()
    fine, coarse = order >= fine_min_order, (order >= 1) & (order <= coarse_max_order)
    n_coarse = int(coarse.sum())
    out = {k: np.empty((h, w), np.float32) for k in ("mean", "texture", "energy")}
    valid = np.empty((h, w), bool)
    lo, hi = clip_levels
    # In bands of block rows: a 12 MP photo's coefficients in float64 would hold 100 MB at once.
    for top in range(0, h, _ROWS_PER_BAND):
        rows = min(_ROWS_PER_BAND, h - top)
        px = luma[top * BLOCK:(top + rows) * BLOCK, :w * BLOCK] * 255.0
        b = px.reshape(rows, BLOCK, w, BLOCK).transpose(0, 2, 1, 3)
        c = dctn(b, axes=(2, 3), norm="ortho").reshape(rows, w, BLOCK * BLOCK)
        c2 = c * c
        fine_ms = c2[..., fine].mean(-1)
        out["mean"][top:top + rows] = c[..., 0] / BLOCK
        out["texture"][top:top + rows] = np.log1p(np.maximum(c2[..., coarse].sum(-1) - n_coarse * fine_ms, 0.0))
        out["energy"][top:top + rows] = np.log(energy_floor + fine_ms)
        valid[top:top + rows] = (b.min(axis=(2, 3)) > lo) & (b.max(axis=(2, 3)) < hi)
    return BlockFeatures(valid=valid, **out)
