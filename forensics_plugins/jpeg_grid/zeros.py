"""Number of zero DCT coefficients of the 8x8 block at every pixel position, and which blocks are flat.

ZERO (Nikoukhah et al., CVPRW 2019; IPOL 2021) counts, for the 8x8 block
whose top-left corner is at each pixel, the AC coefficients of the orthonormal
DCT-II of the integer luminance with ``|c| < 0.5``. JPEG sets most
coefficients of its own blocks to zero, and after decoding and rounding to
integers a coefficient quantised to zero stays within half a grey level of
zero, so blocks aligned with the compression grid hold far more zeros than
blocks straddling it. The DC coefficient is left out: it is the block's mean,
zero only on black, and says nothing about the grid.

A block constant along x (every row constant) or along y (every column
constant) has zeros on every grid (sky, clipped highlights, black borders, a
horizon or a wall of vertical stripes): such blocks are marked so that their
count cannot carry a vote.

One DCT per pixel position is 12 M transforms on a 12 MP photo. They are
computed separably on sliding windows: the 8-point DCT of every horizontal
run of 8 pixels once per row, then the 8-point DCT down every column of those,
both by the even/odd split of the DCT matrix (4x4 products instead of 8x8),
in float32, vectorised over the row by numba and compared with the threshold
as they are produced, so no 64-coefficient array is ever stored. ``fastmath``
lets the compiler fuse multiply-adds: counts are identical from run to run on
one machine, but a coefficient within about 1e-5 of the threshold may be
counted differently on a processor with other vector instructions.
"""

from __future__ import annotations

import numba as nb
import numpy as np

ZERO_THRESHOLD = 0.5


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
def _column_pass(a0, a1, a2, a3, a4, a5, a6, a7, count, t, ev, od, n, first):
    """8-point DCT of ``a0..a7`` (rows of one row-DCT coefficient) at each of ``n`` columns; adds those below t.

    ``first`` marks the pass over the row-DCT's DC, whose own DC (the block's
    DC coefficient) is not counted. ``count`` (shape (n,), int16) gathers
    the counts, ``t`` is the zero threshold and ``ev``, ``od`` the even and
    odd halves of the DCT matrix. The eight rows come apart so that the
    inlined loop reads each as its own array. All fourteen are positional
    because numba's ``inline="always"`` pass fails to type a call that binds
    arguments by keyword (numba 0.68), and the inlining is what makes this
    pass fast.
    """
    e00, e01, e02, e03 = ev[0, 0], ev[0, 1], ev[0, 2], ev[0, 3]
    e10, e11, e12, e13 = ev[1, 0], ev[1, 1], ev[1, 2], ev[1, 3]
    e20, e21, e22, e23 = ev[2, 0], ev[2, 1], ev[2, 2], ev[2, 3]
    e30, e31, e32, e33 = ev[3, 0], ev[3, 1], ev[3, 2], ev[3, 3]
    o00, o01, o02, o03 = od[0, 0], od[0, 1], od[0, 2], od[0, 3]
    o10, o11, o12, o13 = od[1, 0], od[1, 1], od[1, 2], od[1, 3]
    o20, o21, o22, o23 = od[2, 0], od[2, 1], od[2, 2], od[2, 3]
    o30, o31, o32, o33 = od[3, 0], od[3, 1], od[3, 2], od[3, 3]
    keep_dc = np.int16(0) if first else np.int16(1)
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
        count[x] += (keep_dc * np.int16(v0 < t) + np.int16(v1 < t) + np.int16(v2 < t) + np.int16(v3 < t)
                     + np.int16(w0 < t) + np.int16(w1 < t) + np.int16(w2 < t) + np.int16(w3 < t))


@nb.njit(cache=True, fastmath=True)
def _counts(img, t, ev, od, strip):
    h, w = img.shape
    nh, nw = h - 7, w - 7
    out = np.empty((nh, nw), np.uint8)
    rowdct = np.empty((strip + 7, 8, nw), np.float32)
    count = np.empty(nw, np.int16)
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
            count[:] = 0
            for u in range(8):
                _column_pass(rowdct[r, u], rowdct[r + 1, u], rowdct[r + 2, u], rowdct[r + 3, u],
                             rowdct[r + 4, u], rowdct[r + 5, u], rowdct[r + 6, u], rowdct[r + 7, u],
                             count, t, ev, od, nw, u == 0)
            for x in range(nw):
                out[y, x] = count[x]
    return out


@nb.njit(cache=True)
def _flat(img):
    h, w = img.shape
    nh, nw = h - 7, w - 7
    # row_run[y, x]: pixels x..x+7 of row y are equal; col_run[y, x]: pixels y..y+7 of column x are.
    row_run = np.zeros((h, nw), np.bool_)
    for y in range(h):
        equal = 0
        for x in range(1, w):
            equal += img[y, x] == img[y, x - 1]
            if x >= 8:
                equal -= img[y, x - 7] == img[y, x - 8]
            if x >= 7:
                row_run[y, x - 7] = equal == 7
    col_run = np.zeros((nh, w), np.bool_)
    equal_col = np.zeros(w, np.int16)
    for y in range(1, h):
        for x in range(w):
            equal_col[x] += img[y, x] == img[y - 1, x]
            if y >= 8:
                equal_col[x] -= img[y - 7, x] == img[y - 8, x]
            if y >= 7:
                col_run[y - 7, x] = equal_col[x] == 7
    out = np.zeros((nh, nw), np.bool_)
    rows_const = np.zeros(nw, np.int16)
    for y in range(h):
        for x in range(nw):
            rows_const[x] += row_run[y, x]
            if y >= 8:
                rows_const[x] -= row_run[y - 8, x]
        if y >= 7:
            yb = y - 7
            cols_const = 0
            for x in range(w):
                cols_const += col_run[yb, x]
                if x >= 8:
                    cols_const -= col_run[yb, x - 8]
                if x >= 7:
                    out[yb, x - 7] = rows_const[x - 7] == 8 or cols_const == 8
    return out


def zero_counts(luminance: np.ndarray, strip: int = 64) -> np.ndarray:
    """Count the zero AC coefficients of the DCT of every 8x8 block.

    Parameters
    ----------
    luminance : ndarray, shape (H, W)
        Luminance in grey levels (0-255 scale), integer-valued as the decoder
        rounded it; H, W >= 8.
    strip : int
        Rows of block positions computed per pass (working memory
        ``(strip + 7) * 8 * W`` float32).

    Returns
    -------
    ndarray, shape (H - 7, W - 7), uint8
        Entry ``[y, x]`` is the number (0-63) of AC coefficients with
        ``|c| <`` :data:`ZERO_THRESHOLD` (``c`` the orthonormal DCT-II
        coefficient in grey levels) of the block whose top-left pixel is
        ``(x, y)``.

    References
    ----------
    T. Nikoukhah, J. Anger, M. Colom, J.-M. Morel, R. Grompone von Gioi, ZERO: a Local JPEG Grid Origin Detector
    Based on the Number of DCT Zeros and its Applications in Image Forensics, IPOL 11 (2021), pp. 396-433.
    """
    img = np.ascontiguousarray(luminance, dtype=np.float32)
    if img.ndim != 2 or min(img.shape) < 8:
        raise ValueError(f"need a 2-D image of at least 8x8 pixels, got shape {img.shape}")
    return _counts(img, np.float32(ZERO_THRESHOLD), _EVEN, _ODD, int(strip))


def flat_blocks(luminance: np.ndarray) -> np.ndarray:
    """Blocks constant along x (every row constant) or along y (every column constant).

    Parameters
    ----------
    luminance : ndarray, shape (H, W)
        As for :func:`zero_counts`.

    Returns
    -------
    ndarray, shape (H - 7, W - 7), bool
        Entry ``[y, x]`` for the block whose top-left pixel is ``(x, y)``.
    """
    img = np.ascontiguousarray(luminance, dtype=np.float32)
    if img.ndim != 2 or min(img.shape) < 8:
        raise ValueError(f"need a 2-D image of at least 8x8 pixels, got shape {img.shape}")
    return _flat(img)
