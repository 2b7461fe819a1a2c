"""Two demosaicing algorithms, used to make raw-like test photos.

``bilinear``
    each missing sample is the mean of its nearest sampled neighbours of the
    same colour (two or four), the reference linear demosaicing of
    Popescu & Farid (2005, sec. II).
``hamilton_adams``
    the edge-directed algorithm of Hamilton & Adams (US patent 5,629,734,
    1997): green is interpolated along the direction (horizontal or
    vertical) of the smaller gradient, corrected by the second derivative of
    the sampled colour; red and blue follow as green plus interpolated colour
    differences, along the diagonal of smaller gradient where the red or blue
    neighbours are diagonal.

Both are vectorised over the whole image; borders are mirrored without
repeating the edge pixel, which keeps the Bayer phase of the padding.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .bayer import masks

ALGORITHMS = ("bilinear", "hamilton_adams")

_K_GREEN = np.array([[0, 1, 0], [1, 4, 1], [0, 1, 0]], dtype=np.float64) / 4.0
_K_RED_BLUE = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]], dtype=np.float64) / 4.0


def bilinear(raw: np.ndarray, pattern: str) -> np.ndarray:
    """Bilinear demosaicing.

    Parameters
    ----------
    raw : ndarray, shape (H, W)
        Single-plane raw image (any linear scale).
    pattern : str
        Bayer pattern of ``raw`` (see :mod:`.bayer`).

    Returns
    -------
    ndarray, shape (H, W, 3), float64
        R, G, B; sampled values are kept exactly.
    """
    raw = np.asarray(raw, dtype=np.float64)
    m = masks(pattern, raw.shape)
    out = np.empty(raw.shape + (3,))
    for c, kernel in ((0, _K_RED_BLUE), (1, _K_GREEN), (2, _K_RED_BLUE)):
        out[..., c] = ndimage.correlate(raw * m[c], kernel, mode="mirror")
    return out


class _Shifts:
    """Neighbours of every pixel of an image, as views of one mirrored copy."""

    def __init__(self, image: np.ndarray, pad: int = 2):
        self.pad = pad
        self.shape = image.shape
        self.padded = np.pad(image, pad, mode="reflect")

    def __call__(self, dy: int, dx: int) -> np.ndarray:
        p, (h, w) = self.pad, self.shape
        return self.padded[p + dy: p + dy + h, p + dx: p + dx + w]


def _directional(a: np.ndarray, b: np.ndarray, grad_a: np.ndarray, grad_b: np.ndarray) -> np.ndarray:
    """``a`` where its gradient is smaller, ``b`` where that one is, their mean on ties."""
    return np.where(grad_a < grad_b, a, np.where(grad_b < grad_a, b, 0.5 * (a + b)))


def hamilton_adams(raw: np.ndarray, pattern: str) -> np.ndarray:
    """Hamilton-Adams edge-directed demosaicing.

    Parameters
    ----------
    raw : ndarray, shape (H, W)
        Single-plane raw image (any linear scale).
    pattern : str
        Bayer pattern of ``raw``.

    Returns
    -------
    ndarray, shape (H, W, 3), float64
        R, G, B; sampled values are kept exactly.
    """
    raw = np.asarray(raw, dtype=np.float64)
    m_red, m_green, m_blue = masks(pattern, raw.shape)
    s = _Shifts(raw)

    # Green at red and blue sites: the mean of the two green neighbours along
    # the flatter direction plus half the second difference of the centre
    # colour along it (the patent's Laplacian correction).
    lap_h = 2.0 * raw - s(0, -2) - s(0, 2)
    lap_v = 2.0 * raw - s(-2, 0) - s(2, 0)
    g_h = 0.5 * (s(0, -1) + s(0, 1)) + 0.25 * lap_h
    g_v = 0.5 * (s(-1, 0) + s(1, 0)) + 0.25 * lap_v
    grad_h = np.abs(s(0, -1) - s(0, 1)) + np.abs(lap_h)
    grad_v = np.abs(s(-1, 0) - s(1, 0)) + np.abs(lap_v)
    green = np.where(m_green, raw, _directional(g_h, g_v, grad_h, grad_v))

    g = _Shifts(green)
    out = np.empty(raw.shape + (3,))
    out[..., 1] = green
    for c, mine, other in ((0, m_red, m_blue), (2, m_blue, m_red)):
        # Colour difference (channel minus green) known at this channel's sites.
        diff = _Shifts(np.where(mine, raw - green, 0.0))
        mine_s = _Shifts(mine.astype(np.float64))
        # At green sites the two same-colour neighbours lie either left/right or up/down.
        horiz = mine_s(0, -1) > 0
        along_h = 0.5 * (diff(0, -1) + diff(0, 1))
        along_v = 0.5 * (diff(-1, 0) + diff(1, 0))
        at_green = green + np.where(horiz, along_h, along_v)
        # At the opposite colour's sites the neighbours are the four diagonals.
        d1 = 0.5 * (diff(-1, -1) + diff(1, 1))
        d2 = 0.5 * (diff(-1, 1) + diff(1, -1))
        ch = _Shifts(np.where(mine, raw, 0.0))
        grad_1 = np.abs(ch(-1, -1) - ch(1, 1)) + np.abs(2.0 * green - g(-1, -1) - g(1, 1))
        grad_2 = np.abs(ch(-1, 1) - ch(1, -1)) + np.abs(2.0 * green - g(-1, 1) - g(1, -1))
        at_other = green + _directional(d1, d2, grad_1, grad_2)
        out[..., c] = np.where(mine, raw, np.where(other, at_other, at_green))
    return out


def demosaic(raw: np.ndarray, pattern: str, algorithm: str) -> np.ndarray:
    """Demosaic ``raw`` with one of :data:`ALGORITHMS`; returns shape (H, W, 3)."""
    if algorithm == "bilinear":
        return bilinear(raw, pattern)
    if algorithm == "hamilton_adams":
        return hamilton_adams(raw, pattern)
    raise ValueError(f"unknown demosaicing algorithm {algorithm!r}; known: {', '.join(ALGORITHMS)}")
