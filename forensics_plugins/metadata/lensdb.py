"""Look up the lens the EXIF names in the lensfun database.

The database is the one ``lensfunpy`` bundles (lensfun 0.3 format, CC BY-SA
3.0); it is read offline and the user's or system's lensfun files are
ignored, so the same EXIF always gives the same answer. The camera is found
by EXIF Make and Model (0x010F, 0x0110) with lensfun's strict matching (its
loose matching names other cameras, e.g. an iPhone XS for an iPhone 6). The
lens is found by EXIF LensModel (0xA434) among the lenses that fit the
camera's mount; without one, a camera whose mount has exactly one lens (a
compact's fixed lens) gives that lens. The distortion calibration is
interpolated at the EXIF FocalLength (0x920A) by lensfun.
"""

from __future__ import annotations

import functools
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape

import lensfunpy

# lensfun's default calibration aspect ratio when a lens entry states none
# (lensfun documentation of <aspect-ratio>: 3:2).
DEFAULT_ASPECT = 1.5
# lensfun clamps the focal length to the lens's range when it interpolates; a
# focal length further outside than this share of it means the lens is not the one.
_FOCAL_MARGIN = 0.02


@dataclass(frozen=True)
class LensData:
    """A lens identified in lensfun and its distortion at the photo's focal length.

    Attributes
    ----------
    camera_maker, camera_model : str
        lensfun's names for the camera.
    camera_crop : float
        The camera's crop factor (35 mm diagonal / sensor diagonal).
    lens_maker, lens_model : str
        lensfun's names for the lens.
    calibration_crop : float
        Crop factor of the sensor the lens was calibrated on.
    calibration_aspect : float
        Long / short side of that sensor.
    focal_mm : float
        EXIF focal length at which the calibration was interpolated, mm.
    model : {"poly3", "poly5", "ptlens"}
    terms : tuple of float
        The model's coefficients (``k1``; ``k1, k2``; ``a, b, c``).
    matched_by : str
        How the lens was chosen, for the report.
    """

    camera_maker: str
    camera_model: str
    camera_crop: float
    lens_maker: str
    lens_model: str
    calibration_crop: float
    calibration_aspect: float
    focal_mm: float
    model: str
    terms: tuple[float, ...]
    matched_by: str


@dataclass(frozen=True)
class Lookup:
    """The outcome of a lookup: ``data`` when the lens was found, else ``reason`` says why not."""

    data: LensData | None
    reason: str | None = None


@functools.lru_cache(maxsize=1)
def database() -> lensfunpy.Database:
    """The bundled lensfun database, loaded once per process."""
    return lensfunpy.Database(load_common=False, load_bundled=True)


def database_files() -> list[Path]:
    """The XML files of the bundled database."""
    return sorted((Path(lensfunpy.__file__).parent / "db_files").glob("*.xml"))


def _ratio(text: str | None) -> float | None:
    if not text:
        return None
    m = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*(?::\s*(\d+(?:\.\d+)?))?\s*", text)
    if not m:
        return None
    value = float(m.group(1)) / float(m.group(2)) if m.group(2) else float(m.group(1))
    return max(value, 1.0 / value) if value > 0 else None


@functools.lru_cache(maxsize=64)
def calibration_aspect(maker: str, model: str) -> float:
    """The ``<aspect-ratio>`` of a lens entry (long / short), which lensfunpy does not expose.

    Only the database files that contain the lens's model name are parsed.
    Falls back to lensfun's default, 3:2.
    """
    needle = escape(model).encode("utf-8")
    for path in database_files():
        raw = path.read_bytes()
        if needle not in raw:
            continue
        for lens in ET.fromstring(raw).iter("lens"):
            # lensfun may return a name in the user's language, so every variant counts.
            names = [m.text for m in lens.findall("model")]
            makers = [m.text for m in lens.findall("maker")]
            if model in names and maker in makers:
                return _ratio(lens.findtext("aspect-ratio")) or DEFAULT_ASPECT
    return DEFAULT_ASPECT


def normalise_lens_text(text: str) -> str:
    """EXIF lens text in lensfun's spelling: ``18.0-70.0 mm f/3.5-4.5`` -> ``18-70mm f/3.5-4.5``."""
    text = re.sub(r"(\d+)\.0\b", r"\1", text)
    return re.sub(r"(\d)\s+mm\b", r"\1mm", text).strip()


def _lens_candidates(db: lensfunpy.Database, camera: lensfunpy.Camera, lens_model: str | None) -> tuple[list, str]:
    """Lenses matching the EXIF LensModel, else all lenses of the camera's mount, and how they were found."""
    if lens_model:
        for text in dict.fromkeys((lens_model, normalise_lens_text(lens_model))):
            found = db.find_lenses(camera, None, text, False)
            if found:
                return found, f"EXIF LensModel {_short(text)!r}"
    return db.find_lenses(camera), "the only lens lensfun lists for the camera's mount"


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[:limit] + "..."


def _name(maker: str, model: str) -> str:
    first = maker.split()[0].casefold() if maker.split() else ""
    return model if first and model.casefold().startswith(first) else f"{maker} {model}".strip()


def lookup(make: str | None, model: str | None, lens_model: str | None, focal_mm: float | None) -> Lookup:
    """Find the camera and lens the EXIF names and their calibration at ``focal_mm``.

    Parameters
    ----------
    make, model : str or None
        EXIF Make and Model.
    lens_model : str or None
        EXIF LensModel.
    focal_mm : float or None
        EXIF FocalLength, mm (the real, not the 35 mm equivalent, focal length).

    Returns
    -------
    Lookup
        With ``data``, or ``reason`` in a sentence fragment ("the camera ... is not in ...").
    """
    if not make or not model:
        return Lookup(None, "the EXIF names no camera make and model")
    db = database()
    cameras = db.find_cameras(make, model, False)
    if not cameras:
        return Lookup(None, f"the camera {_short(make)} {_short(model)} is not in the lensfun database")
    camera = cameras[0]
    if focal_mm is None or not focal_mm > 0:
        return Lookup(None, "the EXIF gives no focal length")
    lenses, matched_by = _lens_candidates(db, camera, lens_model)
    if not lenses:
        return Lookup(None, f"lensfun has no lens data for the {_name(camera.maker, camera.model)}")
    if len(lenses) > 1:
        camera_text = _name(camera.maker, camera.model)
        if matched_by.startswith("EXIF LensModel"):
            what = f"{matched_by} matches {len(lenses)} lenses"
        elif lens_model:
            what = (f"EXIF LensModel {_short(lens_model)!r} matches no lensfun lens, and lensfun lists "
                    f"{len(lenses)} lenses")
        else:
            what = f"the EXIF names no lens (no LensModel), and lensfun lists {len(lenses)} lenses"
        return Lookup(None, f"{what} for the {camera_text}, so the lens is not identified")
    lens = lenses[0]
    if lens.type != lensfunpy.LensType.RECTILINEAR:
        return Lookup(None, f"the lens {lens.model} is not rectilinear ({lens.type.name.lower()})")
    lo, hi = lens.min_focal, lens.max_focal
    if lo and hi and not lo * (1 - _FOCAL_MARGIN) <= focal_mm <= hi * (1 + _FOCAL_MARGIN):
        return Lookup(None, f"the EXIF focal length {focal_mm:g} mm lies outside the {lo:g}-{hi:g} mm of "
                            f"{lens.model}, so the lens is not the one lensfun lists")
    calib = lens.interpolate_distortion(float(focal_mm))
    if calib is None or calib.model == lensfunpy.DistortionModel.NONE:
        return Lookup(None, f"lensfun has no distortion calibration for {lens.model}")
    return Lookup(LensData(
        camera_maker=camera.maker,
        camera_model=camera.model,
        camera_crop=float(camera.crop_factor),
        lens_maker=lens.maker,
        lens_model=lens.model,
        calibration_crop=float(lens.crop_factor),
        calibration_aspect=calibration_aspect(lens.maker, lens.model),
        focal_mm=float(focal_mm),
        model=calib.model.name.lower(),
        terms=tuple(float(t) for t in calib.terms),
        matched_by=matched_by,
    ))
