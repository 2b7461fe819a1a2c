"""Number of near-zero DCT coefficients of the 8x8 block at every pixel position.

ZERO (Nikoukhah et al., CVPRW 2019; IPOL 2021) counts, for
the 8x8 block whose top-left corner is at each pixel, the DCT-II coefficients
of the decoded luminance that quantise to zero. JPEG sets most coefficients of
its own blocks to zero, so blocks aligned with the compression grid hold far
more zeros than blocks straddling it.

One DCT per pixel position is 12 M transforms on a 12 MP photo. They are
computed separably on sliding windows: the 8-point DCT of every horizontal
run of 8 pixels once per row, then the 8-point DCT down every column of those,
both by the even/odd split of the DCT matrix (4x4 products instead of 8x8),
in float32, vectorised over the row by numba and compared with the thresholds
as they are produced, so no 64-coefficient array is ever stored. ``fastmath``
lets the compiler fuse multiply-adds: counts are identical from run to run on
one machine, but a coefficient within about 1e-5 of a threshold may be counted
differently on a processor with other vector instructions.
"""

from __future__ import annotations

import numba as nb
import numpy as np


def dct_matrix() -> np.ndarray:
    """Orthonormal 8-point DCT-II matrix, shape (8, 8): ``C = D @ block @ D.T``."""
    k = np.arange(8)
    d = np.cos(np.pi * (2 * k[None, :] + 1) * k[:, None] / 16.0) * np.sqrt(2.0 / 8.0)
    d[0] /= np.sqrt(2.0)
    return d


_D = dct_matrix()
# Row u of the DCT is symmetric in the samples for even u and antisymmetric for
# odd u, so it acts on the 4 sums x_j + x_{7-j} or the 4 differences x_j - x_{7-j}.
_EVEN = np.ascontiguousarray(_D[0::2, :4], dtype=np.float32)
_ODD = np.ascontiguousarray(_D[1::2, :4], dtype=np.float32)


@nb.njit(cache=True, fastmath=True, inline="always")
def _column_pass(a0, a1, a2, a3, a4, a5, a6, a7, c0, c1, t0, t1, ev, od, n):
    """8-point DCT of ``a0..a7`` (rows of one row-DCT coefficient) at each of ``n`` columns; counts below t0, t1."""
    e00, e01, e02, e03 = ev[0, 0], ev[0, 1], ev[0, 2], ev[0, 3]
    e10, e11, e12, e13 = ev[1, 0], ev[1, 1], ev[1, 2], ev[1, 3]
    e20, e21, e22, e23 = ev[2, 0], ev[2, 1], ev[2, 2], ev[2, 3]
    e30, e31, e32, e33 = ev[3, 0], ev[3, 1], ev[3, 2], ev[3, 3]
    o00, o01, o02, o03 = od[0, 0], od[0, 1], od[0, 2], od[0, 3]
    o10, o11, o12, o13 = od[1, 0], od[1, 1], od[1, 2], od[1, 3]
    o20, o21, o22, o23 = od[2, 0], od[2, 1], od[2, 2], od[2, 3]
    o30, o31, o32, o33 = od[3, 0], od[3, 1], od[3, 2], od[3, 3]
    for x in range(n):
        s0 = a0[x] + a7[x]
        d0 = a0[x] - a7[x]
        s1 = a1[x] + a6[x]
        d1 = a1[x] - a6[x]
        s2 = a2[x] + a5[x]
        d2 = a2[x] - a5[x]
        s3 = a3[x] + a4[x]
        d3 = a3[x] - a4[x]
        v0 = abs(e00 * s0 + e01 * s1 + e02 * s2 + e03 * s3)
        v1 = abs(e10 * s0 + e11 * s1 + e12 * s2 + e13 * s3)
        v2 = abs(e20 * s0 + e21 * s1 + e22 * s2 + e23 * s3)
        v3 = abs(e30 * s0 + e31 * s1 + e32 * s2 + e33 * s3)
        w0 = abs(o00 * d0 + o01 * d1 + o02 * d2 + o03 * d3)
        w1 = abs(o10 * d0 + o11 * d1 + o12 * d2 + o13 * d3)
        w2 = abs(o20 * d0 + o21 * d1 + o22 * d2 + o23 * d3)
        w3 = abs(o30 * d0 + o31 * d1 + o32 * d2 + o33 * d3)
        c0[x] += (np.int16(v0 < t0) + np.int16(v1 < t0) + np.int16(v2 < t0) + np.int16(v3 < t0)
                  + np.int16(w0 < t0) + np.int16(w1 < t0) + np.int16(w2 < t0) + np.int16(w3 < t0))
        c1[x] += (np.int16(v0 < t1) + np.int16(v1 < t1) + np.int16(v2 < t1) + np.int16(v3 < t1)
                  + np.int16(w0 < t1) + np.int16(w1 < t1) + np.int16(w2 < t1) + np.int16(w3 < t1))


@nb.njit(cache=True, fastmath=True)
def _counts(img, t0, t1, ev, od, strip):
    h, w = img.shape
    nh, nw = h - 7, w - 7
    out0 = np.empty((nh, nw), np.uint8)
    out1 = np.empty((nh, nw), np.uint8)
    rowdct = np.empty((strip + 7, 8, nw), np.float32)
    c0 = np.empty(nw, np.int16)
    c1 = np.empty(nw, np.int16)
    for y0 in range(0, nh, strip):
        y1 = min(nh, y0 + strip)
        for r in range(y1 - y0 + 7):
            p = img[y0 + r]
            for x in range(nw):
                s0 = p[x] + p[x + 7]
                d0 = p[x] - p[x + 7]
                s1 = p[x + 1] + p[x + 6]
                d1 = p[x + 1] - p[x + 6]
                s2 = p[x + 2] + p[x + 5]
                d2 = p[x + 2] - p[x + 5]
                s3 = p[x + 3] + p[x + 4]
                d3 = p[x + 3] - p[x + 4]
                for k in range(4):
                    rowdct[r, 2 * k, x] = ev[k, 0] * s0 + ev[k, 1] * s1 + ev[k, 2] * s2 + ev[k, 3] * s3
                    rowdct[r, 2 * k + 1, x] = od[k, 0] * d0 + od[k, 1] * d1 + od[k, 2] * d2 + od[k, 3] * d3
        for y in range(y0, y1):
            r = y - y0
            c0[:] = 0
            c1[:] = 0
            for u in range(8):
                _column_pass(rowdct[r, u], rowdct[r + 1, u], rowdct[r + 2, u], rowdct[r + 3, u],
                             rowdct[r + 4, u], rowdct[r + 5, u], rowdct[r + 6, u], rowdct[r + 7, u],
                             c0, c1, t0, t1, ev, od, nw)
            for x in range(nw):
                out0[y, x] = c0[x]
                out1[y, x] = c1[x]
    return out0, out1


def zero_counts(luminance: np.ndarray, thresholds: tuple[float, float],
                strip: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Count the near-zero DCT coefficients of every 8x8 block, for two thresholds at once.

    Parameters
    ----------
    luminance : ndarray, shape (H, W)
        Luminance in grey levels (0-255 scale), integer-valued as the decoder
        rounded it; H, W >= 8.
    thresholds : (float, float)
        A coefficient counts as zero for threshold ``t`` when ``|c| < t``, with
        ``c`` the orthonormal DCT-II coefficient in grey levels.
    strip : int
        Rows of block positions computed per pass (working memory
        ``(strip + 7) * 8 * W`` float32).

    Returns
    -------
    (ndarray, ndarray), each shape (H - 7, W - 7), uint8
        Entry ``[y, x]`` is the count (0-64) for the block whose top-left
        pixel is ``(x, y)``, for the first and the second threshold.
    """
    img = np.ascontiguousarray(luminance, dtype=np.float32)
    if img.ndim != 2 or min(img.shape) < 8:
        raise ValueError(f"need a 2-D image of at least 8x8 pixels, got shape {img.shape}")
    return _counts(img, np.float32(thresholds[0]), np.float32(thresholds[1]), _EVEN, _ODD, int(strip))
