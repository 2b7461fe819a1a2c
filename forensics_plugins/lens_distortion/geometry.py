"""Coordinate conventions and the radial distortion model of the paper.

Pixel coordinates are ``(x, y)`` = (column, row) with ``(0, 0)`` at the centre
of the top-left pixel. Normalised coordinates put the image centre
``((W - 1) / 2, (H - 1) / 2)`` at the origin and divide by half the larger
image side, so the larger side spans (-1, 1) (paper, sec. 4.1).

The model (paper eqs. 1-5, with the optional second term and a centre of
distortion ``c`` that the paper fixes at the image centre)::

    p_u = c + (p_d - c) * (1 + k1 * r_d**2 + k2 * r_d**4),   r_d = |p_d - c|

maps distorted (observed) points ``p_d`` to undistorted ones ``p_u``, both
normalised. ``k1 > 0`` is barrel distortion, ``k1 < 0`` pincushion.
"""

from __future__ import annotations

import numpy as np


def norm_scale(shape: tuple[int, ...]) -> float:
    """Pixels per normalised unit: half the larger image side.

    Parameters
    ----------
    shape : tuple
        Image shape ``(H, W, ...)``.
    """
    return max(shape[0], shape[1]) / 2.0


def image_centre(shape: tuple[int, ...]) -> np.ndarray:
    """Image centre in pixels, ``(x, y)``, shape ``(2,)``."""
    return np.array([(shape[1] - 1) / 2.0, (shape[0] - 1) / 2.0])


def to_normalised(points_px: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Pixel ``(x, y)`` points, shape ``(N, 2)``, to normalised coordinates."""
    return (np.asarray(points_px, dtype=np.float64) - image_centre(shape)) / norm_scale(shape)


def to_pixels(points_norm: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Normalised ``(x, y)`` points, shape ``(N, 2)``, to pixel coordinates."""
    return np.asarray(points_norm, dtype=np.float64) * norm_scale(shape) + image_centre(shape)


def undistort(points: np.ndarray, k1: float, k2: float = 0.0, centre=(0.0, 0.0)) -> np.ndarray:
    """Map distorted normalised points to undistorted ones (paper eqs. 4-7).

    Parameters
    ----------
    points : ndarray, shape (N, 2)
        Distorted points, normalised.
    k1, k2 : float
        Radial coefficients (dimensionless, for normalised radii).
    centre : array_like, shape (2,)
        Centre of distortion, normalised.

    Returns
    -------
    ndarray, shape (N, 2)
    """
    c = np.asarray(centre, dtype=np.float64)
    d = np.asarray(points, dtype=np.float64) - c
    r2 = np.einsum("ij,ij->i", d, d)
    return c + d * (1.0 + k1 * r2 + k2 * r2 * r2)[:, None]


def distort(points: np.ndarray, k1: float, k2: float = 0.0, centre=(0.0, 0.0), iterations: int = 30) -> np.ndarray:
    """Inverse of :func:`undistort`: undistorted normalised points to distorted ones.

    Solves ``r_u = r_d (1 + k1 r_d^2 + k2 r_d^4)`` for ``r_d`` by Newton's
    method, vectorised over points; radii where the model folds over
    (derivative <= 0) are not physical and come back as NaN.

    Parameters
    ----------
    points : ndarray, shape (N, 2)
        Undistorted points, normalised.
    k1, k2 : float
    centre : array_like, shape (2,)
    iterations : int
        Newton steps; 30 reach machine precision for |k1| <= 0.5 within r <= 1.5.

    Returns
    -------
    ndarray, shape (N, 2)
    """
    c = np.asarray(centre, dtype=np.float64)
    u = np.asarray(points, dtype=np.float64) - c
    ru = np.hypot(u[:, 0], u[:, 1])
    rd = ru.copy()
    for _ in range(iterations):
        f = rd * (1.0 + k1 * rd**2 + k2 * rd**4) - ru
        df = 1.0 + 3.0 * k1 * rd**2 + 5.0 * k2 * rd**4
        rd = rd - f / np.where(df > 1e-9, df, np.nan)
    df = 1.0 + 3.0 * k1 * rd**2 + 5.0 * k2 * rd**4
    rd = np.where(df > 0, rd, np.nan)
    scale = np.divide(rd, ru, out=np.ones_like(ru), where=ru > 0)
    return c + u * scale[:, None]
