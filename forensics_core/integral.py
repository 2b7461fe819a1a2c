"""Sums over rectangular windows of a map, by its integral image: helpers for detectors that scan windows.

Several detectors ask the same question of a per-block map (votes, flags,
z-scores) over many windows of a photo: how much of it falls inside each?
The integral image (summed-area table) answers every window in four look-ups
[1]_, whatever the window's size.

References
----------
.. [1] F. C. Crow, Summed-area tables for texture mapping, SIGGRAPH 1984,
   Computer Graphics 18(3), pp. 207-212.
"""

from __future__ import annotations

import numpy as np


def integral_image(a: np.ndarray) -> np.ndarray:
    """The summed-area table of ``a`` with a leading row and column of zeros.

    Parameters
    ----------
    a : ndarray, shape (h, w)
        Boolean or integer maps are summed exactly in int64, any other in
        float64.

    Returns
    -------
    ndarray, shape (h + 1, w + 1)
        ``s[i, j]`` is the sum of ``a[:i, :j]``.

    Examples
    --------
    >>> s = integral_image(np.ones((2, 3), dtype=bool))
    >>> int(s[2, 3] - s[0, 3] - s[2, 1] + s[0, 1])  # the window a[0:2, 1:3]
    4
    """
    dtype = np.int64 if a.dtype.kind in "biu" else np.float64
    out = np.zeros((a.shape[0] + 1, a.shape[1] + 1), dtype=dtype)
    out[1:, 1:] = np.cumsum(np.cumsum(a, axis=0, dtype=dtype), axis=1)
    return out


def box_sums(a: np.ndarray, size: int, step: int) -> np.ndarray:
    """Sums of ``a`` over every ``size`` x ``size`` window whose top-left corners are ``step`` apart.

    Parameters
    ----------
    a : ndarray, shape (h, w)
    size, step : int
        Window side and stride, in elements of ``a``.

    Returns
    -------
    ndarray, shape (m, n)
        ``m = (h - size) // step + 1`` rows of windows, ``n`` likewise; the
        dtype of :func:`integral_image`.

    Examples
    --------
    >>> box_sums(np.arange(16.0).reshape(4, 4), 2, 2)
    array([[10., 18.],
           [42., 50.]])
    """
    s = integral_image(a)
    h, w = a.shape
    r = np.arange(0, h - size + 1, step)
    c = np.arange(0, w - size + 1, step)
    return s[np.ix_(r + size, c + size)] - s[np.ix_(r, c + size)] - s[np.ix_(r + size, c)] + s[np.ix_(r, c)]
