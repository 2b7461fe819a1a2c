"""The four Bayer colour-filter-array patterns and their 2 x 2 geometry.

A pattern is named by the colours of its 2 x 2 cell read row by row from the
top-left pixel of the stored grid (``RGGB``: red at ``(0, 0)``, green at
``(0, 1)`` and ``(1, 0)``, blue at ``(1, 1)``). Shifting a pattern by one pixel
horizontally or vertically moves green to the other diagonal; shifting it by
one pixel in both directions keeps green's diagonal and swaps red and blue.
"""

from __future__ import annotations

import numpy as np

PATTERNS = ("RGGB", "GRBG", "GBRG", "BGGR")

CHANNELS = {"R": 0, "G": 1, "B": 2}


def colour_at(pattern: str, row: int, col: int) -> str:
    """Colour the pattern samples at pixel ``(row, col)`` (any integers)."""
    return pattern[2 * (row % 2) + (col % 2)]


def shifted(pattern: str, dy: int, dx: int) -> str:
    """The pattern seen in the stored grid when the sensor's is moved by ``(dy, dx)`` pixels.

    A pixel ``(r, c)`` of the result shows the colour the original samples at
    ``(r + dy, c + dx)``.
    """
    return "".join(colour_at(pattern, r + dy, c + dx) for r in range(2) for c in range(2))


def masks(pattern: str, shape: tuple[int, int]) -> np.ndarray:
    """Boolean sampling masks of the pattern.

    Returns
    -------
    ndarray of bool, shape (3, H, W)
        ``masks[c]`` is True where the sensor samples channel ``c`` (R, G, B).
    """
    out = np.zeros((3,) + tuple(shape), dtype=bool)
    for i, colour in enumerate(pattern):
        row, col = divmod(i, 2)
        out[CHANNELS[colour], row::2, col::2] = True
    return out


def mosaic(rgb: np.ndarray, pattern: str) -> np.ndarray:
    """Sample a full-colour image through the pattern.

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3)
    pattern : str
        One of :data:`PATTERNS`.

    Returns
    -------
    ndarray, shape (H, W)
        The single-plane raw image: each pixel holds the one channel its filter passes.
    """
    m = masks(pattern, rgb.shape[:2])
    return np.einsum("hwc,chw->hw", rgb, m.astype(rgb.dtype))
