"""The lens the EXIF names against the distortion the lens detector measured.

lensfun's calibration of the named lens at the EXIF focal length predicts
the photo's radial distortion (:mod:`.lensdb`, :mod:`.conversion`); the lens
detector measures it from the photo's straight lines (its global model,
``details["global_model"]``, read as :class:`forensics_core.RadialDistortion`). With ``d = k1_measured - k1_predicted`` and the
measured standard error ``se``, the detector reports::

    z = d / se

and calls the two in disagreement only when ``|d|`` exceeds the tolerance
``tol`` by more than ``z_crit`` standard errors, ``(|d| - tol) / se > z_crit``
(``z_crit`` two-sided at ``alpha``). The tolerance absorbs what lensfun does
not model: copy-to-copy variation of one lens model, focus distance
(calibrations are made focused far away; close focus changes distortion),
the EXIF focal length being nominal and rounded, and lensfun's interpolation
between calibrated focal lengths. The default, 0.02, is chosen from the
database rather than measured on reference photos: at the wide end of a
zoom ``k1`` changes fast with focal length (Nikon 18-70 mm at 18 mm: 0.0145
per mm, so half a millimetre of EXIF rounding is 0.007), and focus and
copy variation, which lensfun does not record, are taken to be of the same
order (an assumption, not measured here). A tolerance of 0.02 is a radial displacement of 2% of half
the longer side at the middle of the long edge: a lens mismatch smaller than
that is not called.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from scipy.special import ndtri

from forensics_core import DetectorFinding, EvidenceInfo, RadialDistortion, Status

from .checks import Check
from .conversion import Prediction, predict, unit_scale
from .lensdb import LensData, lookup

# Digital zoom and crop modes narrow the field of view the crop factor gives;
# the 35 mm equivalent focal length in EXIF shows them beyond this share.
_CROP_AGREEMENT = 0.10

OUTCOME_WORDS = ("agrees", "disagrees", "no lens data", "prediction does not apply", "lens detector did not measure k1")


@dataclass(frozen=True)
class LensComparison:
    """Everything the lens check established, for the details and the report.

    Attributes
    ----------
    outcome : str
        One of :data:`OUTCOME_WORDS`.
    reason : str or None
        Why there is no comparison, when there is none.
    lens : LensData or None
    prediction : Prediction or None
    measured : dict or None
        ``k1``, ``k1_stderr``, ``k2``, ``k2_stderr`` of the lens detector.
    difference, z : float or None
        ``k1_measured - k1_predicted`` and its z-score.
    """

    outcome: str
    reason: str | None
    lens: LensData | None
    prediction: Prediction | None
    measured: dict[str, float] | None
    difference: float | None
    z: float | None


def _measured(finding: DetectorFinding | None) -> tuple[dict[str, float] | None, str | None]:
    if finding is None:
        return None, "the lens detector did not run in this analysis"
    # An inconclusive lens finding may still carry a model fitted to a few
    # lines; the comparison uses only a measurement the detector stood by.
    if finding.status is not Status.OK:
        return None, f"the lens detector's status is {finding.status.value}"
    model = RadialDistortion.from_finding(finding)
    if model is None:
        return None, "the lens detector found too few straight lines to fit a camera model"
    if not model.k1_stderr > 0:
        return None, "the lens detector gave no k1 with a standard error"
    return {"k1": model.k1, "k1_stderr": model.k1_stderr, "k2": model.k2, "k2_stderr": model.k2_stderr}, None


def _predicted_k1(prediction: Prediction, measured: dict[str, float]) -> float:
    """lensfun's k1 in the measurement's model: the one-term fit where the detector held k2 at zero."""
    return prediction.k1_one_term if measured["k2"] == 0 and measured["k2_stderr"] == 0 else prediction.k1


def _applies(info: EvidenceInfo, lens: LensData, dims_changed: bool | None) -> str | None:
    """Why the prediction does not apply to this image, or None when it does."""
    if dims_changed:
        return (f"the EXIF dimensions {info.exif.exif_image_width} x {info.exif.exif_image_height} differ from the "
                f"stored {info.width} x {info.height}, so the image was resized or cropped (a crop to the same aspect "
                "ratio cannot be told from a resize) and the lens geometry no longer maps onto it")
    f35, f = info.exif.focal_length_35mm, info.exif.focal_length_mm
    if f35 and f and f > 0:
        crop = f35 / f
        if abs(crop / lens.camera_crop - 1) > _CROP_AGREEMENT:
            return (f"the EXIF 35 mm equivalent focal length ({f35:g} mm for {f:g} mm) implies a crop factor of "
                    f"{crop:.2f}, not the camera's {lens.camera_crop:.2f}: digital zoom or a crop mode narrowed the "
                    "frame")
    return None


def compare(info: EvidenceInfo, lens_finding: DetectorFinding | None, dims_changed: bool | None,
            tolerance: float, alpha: float, grid: int) -> LensComparison:
    """Predict the photo's ``k1`` from lensfun and compare it with the lens detector's.

    Parameters
    ----------
    info : EvidenceInfo
        The evidence's properties and EXIF.
    lens_finding : DetectorFinding or None
        The lens detector's finding in this analysis, if it ran.
    dims_changed : bool or None
        Whether EXIF dimensions show a resize or crop.
    tolerance : float
        Absolute ``k1`` tolerance (project units).
    alpha : float
        Two-sided level of the disagreement test.
    grid : int
        Samples along the longer side in the conversion fit.
    """
    exif = info.exif
    found = lookup(exif.make, exif.model, exif.lens_model, exif.focal_length_mm)
    if found.data is None:
        return LensComparison("no lens data", found.reason, None, None, None, None, None)
    lens = found.data
    why_not = _applies(info, lens, dims_changed)
    if why_not:
        return LensComparison("prediction does not apply", why_not, lens, None, None, None, None)
    aspect = max(info.width, info.height) / min(info.width, info.height)
    scale = unit_scale(aspect, lens.calibration_aspect, lens.calibration_crop, lens.camera_crop)
    prediction = predict(lens.model, lens.terms, info.width, info.height, scale, grid)
    if prediction is None:
        return LensComparison("prediction does not apply", "lensfun's model folds over inside this image",
                              lens, None, None, None, None)
    measured, reason = _measured(lens_finding)
    if measured is None:
        return LensComparison("lens detector did not measure k1", reason, lens, prediction, None, None, None)
    d = measured["k1"] - _predicted_k1(prediction, measured)
    se = measured["k1_stderr"]
    z_crit = float(-ndtri(alpha / 2))
    outcome = "disagrees" if (abs(d) - tolerance) / se > z_crit else "agrees"
    return LensComparison(outcome, None, lens, prediction, measured, d, d / se)


def lens_check(cmp: LensComparison, tolerance: float, alpha: float) -> Check:
    """The comparison as one check: agrees -> consistent, disagrees -> note, otherwise not available.

    A disagreement is not called suspicious: on real photos the lens
    detector's k1 scatters far beyond its standard error (from -0.05 to +0.13
    over eleven photos of one camera at one focal length; -0.24 on an
    authentic Pentax Optio 430 frame whose lensfun prediction is +0.005),
    because curved objects pass as straight lines. Measured on 63 camera
    originals, a test at the stated standard error called 2 of 7 comparable
    ones suspicious. The disagreement is reported for the examiner to weigh.
    """
    title = "Lens (lensfun) vs measured distortion"
    if cmp.outcome == "no lens data":
        return Check("lens", title, "not available", f"No lens data: {cmp.reason}.")
    lens = cmp.lens
    source = f"{lens.lens_model} at {lens.focal_mm:g} mm ({lens.model})"
    if cmp.outcome == "prediction does not apply":
        return Check("lens", title, "not available",
                     f"lensfun knows {source}, but the prediction does not apply: {cmp.reason}.")
    pred = cmp.prediction
    if cmp.outcome == "lens detector did not measure k1":
        return Check("lens", title, "not available",
                     f"lensfun predicts k1 = {pred.k1:+.4f} for {source}, but {cmp.reason}.")
    z_crit = float(-ndtri(alpha / 2))
    m = cmp.measured
    model_words = "one-term " if m["k2_stderr"] == 0 and m["k2"] == 0 else ""
    text = (f"lensfun predicts {model_words}k1 = {_predicted_k1(pred, m):+.4f} for {source}; the lens detector measured "
            f"{m['k1']:+.4f} ± {m['k1_stderr']:.4f} (difference {cmp.difference:+.4f}, z = {cmp.z:+.1f}; tolerance "
            f"{tolerance:g}, critical z {z_crit:.2f})")
    if cmp.outcome == "disagrees":
        return Check("lens", title, "note",
                     text + ": the photo's lines do not bend as the named lens bends them. On real photos the measured "
                     "k1 also departs this far when curved objects (arches, bezels, cables) are taken for straight "
                     "lines, so this is an observation to weigh, not a sign of editing.")
    return Check("lens", title, "consistent", text + ": they agree.")


def details(cmp: LensComparison, tolerance: float, alpha: float) -> dict[str, Any]:
    """JSON numbers of the lens comparison."""
    lens, pred = cmp.lens, cmp.prediction
    return {
        "outcome": cmp.outcome,
        "reason": cmp.reason,
        "camera": None if lens is None else f"{lens.camera_maker} {lens.camera_model}",
        "lens": None if lens is None else f"{lens.lens_maker} {lens.lens_model}",
        "matched_by": None if lens is None else lens.matched_by,
        "focal_mm": None if lens is None else lens.focal_mm,
        "model": None if lens is None else lens.model,
        "terms": None if lens is None else [round(t, 7) for t in lens.terms],
        "camera_crop": None if lens is None else round(lens.camera_crop, 4),
        "calibration_crop": None if lens is None else round(lens.calibration_crop, 4),
        "calibration_aspect": None if lens is None else round(lens.calibration_aspect, 4),
        "scale": None if pred is None else round(pred.scale, 5),
        "r_max": None if pred is None else round(pred.r_max, 4),
        "k1_predicted": None if pred is None else round(pred.k1, 5),
        "k2_predicted": None if pred is None else round(pred.k2, 5),
        "k1_predicted_one_term": None if pred is None else round(pred.k1_one_term, 5),
        "magnification": None if pred is None else round(pred.magnification, 5),
        "fit_rms_px": None if pred is None else round(pred.fit_rms_px, 3),
        "k1_measured": None if cmp.measured is None else cmp.measured["k1"],
        "k1_measured_stderr": None if cmp.measured is None else cmp.measured["k1_stderr"],
        "k2_measured": None if cmp.measured is None else cmp.measured.get("k2"),
        "k2_measured_stderr": None if cmp.measured is None else cmp.measured.get("k2_stderr"),
        "difference": None if cmp.difference is None else round(cmp.difference, 5),
        "z": None if cmp.z is None else round(cmp.z, 3),
        "tolerance": tolerance,
        "alpha": alpha,
        "z_crit": round(float(-ndtri(alpha / 2)), 4),
        "units": "k1, k2 normalised: image centre at 0, half the larger side = 1; distorted to undistorted",
    }
