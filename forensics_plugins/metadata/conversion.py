"""lensfun's distortion models in the project's convention: the predicted (k1, k2).

lensfun (``include/lensfun/lensfun.h``, lensfun 0.3) maps an UNDISTORTED
radius ``R_u`` to the DISTORTED one ``R_d``, with radii in units of half the
shorter side of the sensor the lens was calibrated on::

    poly3:   R_d = R_u (1 - k1 + k1 R_u^2)
    poly5:   R_d = R_u (1 + k1 R_u^2 + k2 R_u^4)
    ptlens:  R_d = R_u (a R_u^3 + b R_u^2 + c R_u + 1 - a - b - c)

The project (``forensics_plugins.lens_distortion.geometry``) maps DISTORTED to
UNDISTORTED with radii in units of half the LONGER side of the image::

    r_u = r_d (1 + k1 r_d^2 + k2 r_d^4),      k1 > 0 barrel.

Units. The image is assumed to span the whole sensor of the camera, whose
crop factor ``c_cam`` gives its half-diagonal, 43.27 mm / 2 / ``c_cam``; the
calibration sensor (crop ``c_cal``, aspect ratio ``a_cal``) has half shorter
side 43.27 mm / 2 / ``c_cal`` / hypot(``a_cal``, 1). A point at ``r`` (project
units) of an image with aspect ratio ``a`` (long / short) therefore lies at::

    R = r * s,   s = a / hypot(a, 1) * hypot(a_cal, 1) * c_cal / c_cam

which is ``r * a`` when image and calibration sensor agree (lensfun's own
normalisation, ``lfModifier``; the tests check it against ``lensfunpy.Modifier``).

Fit. Over a grid of distorted positions covering the image (so radii are
weighted as the image's area weights them, as the lines the lens detector
measures are), lensfun's model is inverted for ``r_u`` and the project's
two-term model is fitted by linear least squares::

    r_u = m r_d (1 + k1 r_d^2 + k2 r_d^4)

with a free magnification ``m``: lensfun's models scale the centre by
``1 - a - b - c`` (ptlens) and a uniform scale leaves straight lines straight,
so the lens detector's ``(k1, k2)`` are defined only up to it. The RMS of what
the two terms cannot follow is reported in pixels. A one-term fit (``k2 = 0``)
is reported too, for comparison with ``k1`` values quoted that way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

_NEWTON_STEPS = 40


@dataclass(frozen=True)
class Prediction:
    """The project's model fitted to a lensfun calibration for one image geometry.

    Attributes
    ----------
    k1, k2 : float
        Project convention (normalised by half the longer side; distorted to undistorted).
    k1_one_term : float
        ``k1`` of the fit with ``k2 = 0``, for comparison.
    magnification : float
        ``m`` of the two-term fit.
    scale : float
        ``s`` of the module docstring: lensfun radius per project radius.
    r_max : float
        Largest radius of the image, project units (its corner).
    fit_rms_px : float
        RMS radial displacement, pixels, that the two-term fit leaves.
    """

    k1: float
    k2: float
    k1_one_term: float
    magnification: float
    scale: float
    r_max: float
    fit_rms_px: float


def unit_scale(aspect: float, calibration_aspect: float, calibration_crop: float, camera_crop: float) -> float:
    """``s``: lensfun radius per project radius (see the module docstring).

    Parameters
    ----------
    aspect : float
        Image long / short side.
    calibration_aspect : float
        Calibration sensor long / short side.
    calibration_crop, camera_crop : float
        Crop factors of the calibration sensor and of the camera.
    """
    return aspect / math.hypot(aspect, 1.0) * math.hypot(calibration_aspect, 1.0) * calibration_crop / camera_crop


def forward(model: str, terms: tuple[float, ...], r_u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """lensfun's ``R_d`` and ``dR_d / dR_u`` at undistorted radii ``R_u`` (lensfun units), shape as ``r_u``."""
    r = np.asarray(r_u, dtype=np.float64)
    if model == "poly3":
        (k1,) = terms[:1]
        return r * (1 - k1 + k1 * r**2), 1 - k1 + 3 * k1 * r**2
    if model == "poly5":
        k1, k2 = terms[:2]
        return r * (1 + k1 * r**2 + k2 * r**4), 1 + 3 * k1 * r**2 + 5 * k2 * r**4
    if model == "ptlens":
        a, b, c = terms[:3]
        d = 1 - a - b - c
        return r * (a * r**3 + b * r**2 + c * r + d), 4 * a * r**3 + 3 * b * r**2 + 2 * c * r + d
    raise ValueError(f"unknown lensfun distortion model {model!r}")


def inverse(model: str, terms: tuple[float, ...], r_d: np.ndarray) -> np.ndarray:
    """Undistorted radii ``R_u`` whose lensfun ``R_d`` are ``r_d`` (lensfun units), by Newton's method.

    Returns NaN where the model is not monotonic (it folds over), which no
    physical lens does inside its image.
    """
    r_d = np.asarray(r_d, dtype=np.float64)
    r_u = r_d.copy()
    for _ in range(_NEWTON_STEPS):
        f, df = forward(model, terms, r_u)
        r_u = r_u - (f - r_d) / np.where(df > 1e-9, df, np.nan)
    f, df = forward(model, terms, r_u)
    ok = (df > 0) & (np.abs(f - r_d) < 1e-9 * np.maximum(1.0, r_d))
    return np.where(ok, r_u, np.nan)


def predict(model: str, terms: tuple[float, ...], width: int, height: int, scale: float,
            grid: int = 64) -> Prediction | None:
    """Fit the project's (k1, k2) to lensfun's model over an image of ``width`` x ``height`` pixels.

    Parameters
    ----------
    model : {"poly3", "poly5", "ptlens"}
    terms : tuple of float
    width, height : int
        Image size, pixels (the stored grid).
    scale : float
        From :func:`unit_scale`.
    grid : int
        Samples along the longer side; the shorter side gets proportionally fewer.

    Returns
    -------
    Prediction or None
        None when lensfun's model folds over inside the image.
    """
    long_side, short_side = max(width, height), min(width, height)
    r_max = math.hypot(1.0, short_side / long_side)
    n_short = max(2, round(grid * short_side / long_side))
    half_short = short_side / long_side
    x, y = np.meshgrid(np.linspace(-1.0, 1.0, grid), np.linspace(-half_short, half_short, n_short))
    r_d = np.hypot(x, y).ravel()
    r_d = r_d[r_d > 0]
    r_u = inverse(model, terms, r_d * scale) / scale
    if not np.all(np.isfinite(r_u)):
        return None
    design = np.column_stack([r_d, r_d**3, r_d**5])
    coef, *_ = np.linalg.lstsq(design, r_u, rcond=None)
    m, k1, k2 = coef[0], coef[1] / coef[0], coef[2] / coef[0]
    rms = float(np.sqrt(np.mean((r_u - design @ coef) ** 2)) / m) * long_side / 2.0
    one, *_ = np.linalg.lstsq(design[:, :2], r_u, rcond=None)
    return Prediction(float(k1), float(k2), float(one[1] / one[0]), float(m), float(scale), float(r_max), rms)
