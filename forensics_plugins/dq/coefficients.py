"""The luma DCT coefficients as stored in the file, and their calibrated unquantised estimate.

References
----------
.. [1] T. Bianchi, A. Piva, "Image forgery localization via block-grained
   analysis of JPEG artifacts", IEEE Trans. Information Forensics and
   Security 7(3), 2012, pp. 1003-1017.
.. [2] J. Fridrich, M. Goljan, R. Du, "Steganalysis based on JPEG
   compatibility", Proc. SPIE 4518, 2001 (calibration by cropping).
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass

import jpeglib
import numpy as np
from scipy.fft import dctn, idctn

# Zig-zag order of the 8 x 8 DCT frequencies, as (row, column) flat indices.
ZIGZAG = np.array([0, 1, 8, 16, 9, 2, 3, 10, 17, 24, 32, 25, 18, 11, 4, 5, 12, 19, 26, 33, 40, 48, 41, 34, 27,
                   20, 13, 6, 7, 14, 21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23, 30, 37, 44, 51, 58,
                   59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63])


@dataclass(frozen=True)
class LumaCoefficients:
    """The quantised luma DCT coefficients of a JPEG and what is derived from them.

    Attributes
    ----------
    quantised : ndarray of int32, shape (h, w, 8, 8)
        The stored coefficients, block row, block column, frequency.
    table : ndarray of float, shape (8, 8)
        The luma quantisation table of the last compression.
    height, width : int
        The photo's size in pixels (the blocks may extend past it).
    """

    quantised: np.ndarray
    table: np.ndarray
    height: int
    width: int

    def decoded(self, top: int = 0, bottom: int | None = None) -> np.ndarray:
        """Luma blocks the decoder computes before rounding and clipping, of block rows ``top:bottom``.

        Returns
        -------
        ndarray, shape (bottom - top, w, 8, 8)
            Grey levels.
        """
        return idctn(self.quantised[top:bottom] * self.table, axes=(2, 3), norm="ortho") + 128.0

    def unreliable(self, decoded: np.ndarray, margin: float, top: int = 0) -> np.ndarray:
        """Blocks whose quantisation history cannot be read, boolean, shape ``decoded.shape[:2]``.

        ``decoded`` holds the block rows from ``top`` on. A block with a pixel
        within ``margin`` grey levels of 0 or 255 was probably clipped by an
        earlier decoder, which moves its coefficients off the earlier
        quantisation lattice; a block that extends past the photo's edge was
        padded anew by each encoder.
        """
        bad = ((decoded < margin) | (decoded > 255.0 - margin)).any(axis=(2, 3))
        if self.height % 8:
            bad[max(0, self.height // 8 - top):, :] = True
        if self.width % 8:
            bad[:, self.width // 8:] = True
        return bad

    def scan(self, margin: float, frequencies: np.ndarray, band: int = 32) -> tuple[np.ndarray, np.ndarray]:
        """The unreliable blocks and the calibrated coefficients of ``frequencies``, by bands of block rows.

        Decoding all blocks at once holds several float64 copies of the
        photo (about 0.8 GB each at 100 MP); a band of ``band`` block rows
        holds a few tens of MB, and each block's result is the same.

        Parameters
        ----------
        margin : float
            See :meth:`unreliable`.
        frequencies : ndarray of int, shape (k,)
            Flat indices (row * 8 + column) of the frequencies wanted.
        band : int
            Block rows decoded at a time.

        Returns
        -------
        unreliable : ndarray of bool, shape (h, w)
        unquantised : ndarray of float, shape (h - 1, w - 1, k)
            :func:`calibrated` at the chosen frequencies.
        """
        h, w = self.quantised.shape[:2]
        unreliable = np.empty((h, w), bool)
        unquantised = np.empty((h - 1, w - 1, len(frequencies)))
        rows, cols = np.divmod(np.asarray(frequencies, dtype=int), 8)
        for top in range(0, h, band):
            bottom = min(h, top + band)
            decoded = self.decoded(top, min(h, bottom + 1))
            unreliable[top:bottom] = self.unreliable(decoded[:bottom - top], margin, top)
            if top < h - 1:
                unquantised[top:min(bottom, h - 1)] = calibrated(decoded)[:, :, rows, cols]
        return unreliable, unquantised


def read_luma(data: bytes) -> LumaCoefficients | None:
    """The luma coefficients of a JPEG file's bytes, or None when it has no readable luma component.

    The bytes are those that were hashed; libjpeg (through jpeglib) reads
    them from a private temporary copy, never from the evidence path.
    """
    fd, name = tempfile.mkstemp(suffix=".jpg")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        jpeg = jpeglib.read_dct(name)
        jpeg.load()
        luma = np.asarray(jpeg.Y, dtype=np.int32)
        table = np.asarray(jpeg.qt[int(jpeg.quant_tbl_no[0])], dtype=np.float64)
        return LumaCoefficients(luma, table, int(jpeg.height), int(jpeg.width))
    except (OSError, ValueError, IndexError, TypeError, AttributeError, RuntimeError):
        return None
    finally:
        os.unlink(name)


def calibrated(decoded: np.ndarray) -> np.ndarray:
    """DCT coefficients of the decoded luma on a grid shifted by 4 pixels, shape (h-1, w-1, 8, 8).

    ``decoded`` has shape (h, w, 8, 8), grey levels (:meth:`LumaCoefficients.decoded`).

    Off the compression grid, the coefficients follow (approximately) the
    distribution the photo's content had before any quantisation, which is
    the single-compression model's ingredient ([1]_ section III, the
    calibration of [2]_).
    """
    h, w = decoded.shape[:2]
    pixels = np.clip(np.round(decoded), 0, 255).transpose(0, 2, 1, 3).reshape(h * 8, w * 8)
    shifted = pixels[4:4 + (h - 1) * 8, 4:4 + (w - 1) * 8] - 128.0
    blocks = shifted.reshape(h - 1, 8, w - 1, 8).transpose(0, 2, 1, 3)
    return dctn(blocks, axes=(2, 3), norm="ortho")
