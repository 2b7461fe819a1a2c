"""The check record and the checks that read EXIF tags alone.

Every check ends in one :class:`Check`: an outcome word and one sentence with
the values it saw. ``consistent`` and ``suspicious`` are the applicable
outcomes; ``not available`` means the file does not carry what the check
needs, and ``note`` records something an examiner should read that points
neither way. Metadata is never proof on its own: these are the observations
an examiner makes first, not tests with an error rate.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Literal

from forensics_core import EvidenceInfo

Outcome = Literal["consistent", "suspicious", "not available", "note"]
APPLICABLE: tuple[Outcome, ...] = ("consistent", "suspicious")
# MPO (CIPA DC-007), which phones and stereo cameras write, is JPEG with more pictures after the first.
JPEG_FORMATS = ("JPEG", "MPO")

# Software that re-encodes the pixels when it saves: its name in the Software
# tag means the file went through it after capture. Matched as case-insensitive
# words or phrases, so "GIMP 2.4.5" and "Adobe Photoshop CS2 Macintosh" both hit.
EDITORS = (
    "photoshop", "gimp", "lightroom", "snapseed", "affinity", "paint.net", "pixelmator", "picsart",
    "photoscape", "canva", "camera raw", "capture one", "darktable", "rawtherapee", "luminar",
    "acdsee", "paintshop", "paint shop pro", "corel", "photodirector", "facetune", "vsco", "fotor",
    "polarr", "pixlr", "krita", "photopea", "picasa", "iphoto", "aperture", "photo editor",
    "photos editor", "meitu", "airbrush", "lensa", "remini", "photoworks", "movavi", "inpaint",
)
# Tools that copy files off a camera and may rewrite the EXIF (DateTime,
# Software) without re-encoding the pixels: worth a note, not a suspicion.
TRANSFER_TOOLS = ("nikon transfer", "viewnx", "zoombrowser", "imagebrowser", "windows photo gallery",
                  "image transfer", "pentax photo browser", "olympus master", "exiftool")
# Camera firmware writes a bare version number, possibly after "Ver" or
# "Firmware" ("Ver.1.00", "1.00", "v981-79", "Firmware Version 1.0.2"), or its
# model name with one ("Digital Camera DX-10 Ver1.00"); a program's name with
# a version is not firmware, so a name is accepted only when it is the camera's.
_VERSION = r"(?:firmware\s*)?(?:v(?:er(?:sion)?)?\.?\s*)?\d+[a-z]?(?:[.\-_]\d+[a-z]?)*"
_FIRMWARE = re.compile(rf"^{_VERSION}$", re.I)
_ENDS_WITH_VERSION = re.compile(rf"\b{_VERSION}$", re.I)
# A firmware build id is one token of letters and digits ("J327T1UVS4ASH2",
# "D1v024j", "HD7.01.01.90.00"): at least three digits and no run of more
# than three letters, which a program's name has.
_BUILD_ID = re.compile(r"^(?=(?:[^0-9]*[0-9]){3})(?![^ ]*[a-z]{4})[a-z0-9][a-z0-9.\-_]{2,23}$", re.I)
_EXIF_DATE = re.compile(r"^\s*(\d{4}):(\d{2}):(\d{2})[ T](\d{2}):(\d{2}):(\d{2})\s*$")


@dataclass(frozen=True)
class Check:
    """One examiner check and what it found.

    Attributes
    ----------
    id : str
        Stable identifier (``software``, ``datetime``, ...).
    title : str
        What was checked, for the report's table.
    outcome : {"consistent", "suspicious", "not available", "note"}
    observation : str
        One sentence giving the values the outcome rests on.
    """

    id: str
    title: str
    outcome: Outcome
    observation: str


def _quoted(text: str, limit: int = 80) -> str:
    return repr(text if len(text) <= limit else text[:limit] + "...")


def exif_presence(info: EvidenceInfo) -> Check:
    """Whether the file carries EXIF at all, and whether it names a camera."""
    title = "EXIF present"
    exif = info.exif
    if exif.unreadable:
        # A camera writes well-formed EXIF; a broken header is a note, not a
        # suspicion: storage faults and careless tools break it too.
        return Check("exif_present", title, "note", f"{exif.unreadable}: a camera writes well-formed EXIF, so the "
                     "file is not as the camera wrote it, which says nothing by itself about the pixels.")
    if not exif.raw:
        # Not "suspicious": messengers, social networks, web uploads and
        # research data sets strip EXIF from authentic photos routinely (every
        # authentic photo of two public forgery data sets lacks it), so its
        # absence says nothing about the pixels.
        if info.format in JPEG_FORMATS:
            return Check("exif_present", title, "note",
                         "The JPEG carries no EXIF at all, which a camera always writes: the file is not as the "
                         "camera wrote it, but messengers, social networks and web uploads strip EXIF from untouched "
                         "photos too, so this says nothing about whether the pixels were changed.")
        return Check("exif_present", title, "note",
                     f"The {info.format} file carries no EXIF; cameras seldom write {info.format}, so there is "
                     "nothing to compare with.")
    if exif.make is None and exif.model is None:
        return Check("exif_present", title, "note",
                     f"EXIF is present ({len(exif.raw)} tags) but names no camera make or model.")
    camera = camera_name(exif.make, exif.model)
    return Check("exif_present", title, "consistent",
                 f"EXIF is present ({len(exif.raw)} tags) and names the camera {_quoted(camera)}.")


def camera_name(make: str | None, model: str | None) -> str:
    """Make and model as one name, without repeating a make the model already starts with."""
    if make and model and model.casefold().startswith(make.split()[0].casefold() if make.split() else "\0"):
        return model
    return " ".join(v for v in (make, model) if v)


def classify_software(software: str, make: str | None = None, model: str | None = None) -> str:
    """Kind of program a Software tag names.

    Returns
    -------
    str
        ``"editor"`` (re-encodes pixels), ``"transfer"`` (copies and rewrites
        metadata), ``"firmware"`` (a camera's version string or model name) or
        ``"unknown"``.
    """
    low = software.casefold()
    words = re.sub(r"[^a-z0-9.]+", " ", low)
    if any(re.search(rf"(?<![a-z]){re.escape(e)}(?![a-z])", words) for e in EDITORS):
        return "editor"
    if any(t in words for t in TRANSFER_TOOLS):
        return "transfer"
    text = software.strip()
    if _FIRMWARE.match(text) or _BUILD_ID.match(text):
        return "firmware"
    names = [n.strip().casefold() for n in (model, make) if n and len(n.strip()) >= 3]
    # A model name often repeats the make ("Canon PowerShot SX60 HS",
    # "PENTAX *ist DL"); its last word, or what follows the make, is enough to
    # recognise it inside a firmware string.
    names += [n.split()[-1] for n in names if len(n.split()) > 1 and len(n.split()[-1]) >= 3]
    names += [n.split(None, 1)[1] for n in names if len(n.split()) > 1 and len(n.split(None, 1)[1]) >= 3]
    if _ENDS_WITH_VERSION.search(text) and any(n in low for n in names):
        return "firmware"
    # Phones name their build after the model ("SM-N900A": "N900AUCUCNC2").
    parts = [p.casefold() for p in re.split(r"[\s\-_]+", model or "") if len(p) >= 4 and re.search(r"\d", p)]
    if " " not in text and any(low.startswith(p) for p in parts):
        return "firmware"
    return "unknown"


def software_tag(info: EvidenceInfo, xmp_agents: Sequence[tuple[str, str]] = ()) -> Check:
    """The Software tag (0x0131) and the programs XMP names: an editor's name means the file was saved by it.

    ``xmp_agents`` are ``(kind, name)`` pairs from :func:`.xmp.xmp_agents`.
    An editor as XMP ``CreatorTool`` made the file and is suspicious as in
    the Software tag; an editor only in the XMP history is a note, because
    catalogue programs (Bridge, Lightroom, Camera Raw) record metadata-only
    saves of an untouched JPEG there too.
    """
    title = "Software tag and XMP"
    sw = info.exif.software
    creators = [n for k, n in xmp_agents if k == "creator" and classify_software(n) == "editor"]
    history = [n for k, n in xmp_agents if k == "history" and classify_software(n) == "editor"]
    if sw is not None and classify_software(sw, info.exif.make, info.exif.model) == "editor":
        return Check("software", title, "suspicious",
                     f"The Software tag reads {_quoted(sw)}, an image editor: the file was saved by it after capture.")
    if creators:
        return Check("software", title, "suspicious",
                     f"The XMP names {_quoted(creators[0])} as the program that created the file (CreatorTool), an "
                     "image editor: the file was saved by it after capture.")
    if history:
        return Check("software", title, "note",
                     f"The XMP history names {_quoted(history[0])}, an image editor; such entries are also written "
                     "by metadata-only edits, so they do not show that the pixels changed.")
    if sw is None:
        return Check("software", title, "not available", "The file has no Software tag and no XMP naming an editor.")
    kind = classify_software(sw, info.exif.make, info.exif.model)
    if kind == "transfer":
        return Check("software", title, "note",
                     f"The Software tag reads {_quoted(sw)}, a transfer or cataloguing tool that rewrites metadata "
                     "but is not known to change pixels.")
    if kind == "firmware":
        return Check("software", title, "consistent",
                     f"The Software tag reads {_quoted(sw)}, a camera firmware version string.")
    return Check("software", title, "note",
                 f"The Software tag reads {_quoted(sw)}, which is neither a known editor nor a firmware version "
                 "string.")


def parse_exif_datetime(text: str | None) -> datetime | None:
    """An EXIF ``YYYY:MM:DD HH:MM:SS`` string as a naive datetime, or None when malformed."""
    if text is None:
        return None
    m = _EXIF_DATE.match(text)
    if not m:
        return None
    try:
        return datetime(*(int(g) for g in m.groups()))
    except ValueError:
        return None


def exposure_time_s(info: EvidenceInfo) -> float | None:
    """ExposureTime (0x829A) in seconds from the raw tags, or None."""
    for tag in info.exif.raw:
        if tag.name == "ExposureTime":
            try:
                value = float(tag.value)
            except ValueError:
                return None
            return value if math.isfinite(value) and value >= 0 else None
    return None


def datetimes(info: EvidenceInfo, tolerance_s: float) -> Check:
    """DateTime (0x0132, last change) against DateTimeOriginal (0x9003, capture).

    A camera writes both at capture; a later DateTime means a program saved
    the file afterwards. ``tolerance_s`` allows for cameras that stamp them at
    slightly different moments of the write. DateTimeOriginal marks the
    shutter release and a camera may stamp DateTime when it writes the file,
    after the exposure and, with long-exposure noise reduction, a dark frame
    as long again: a later DateTime is therefore accepted up to
    ``tolerance_s`` + 2 x ExposureTime.
    """
    title = "DateTime vs DateTimeOriginal"
    raw_mod, raw_orig = info.exif.datetime, info.exif.datetime_original
    if raw_mod is None or raw_orig is None:
        missing = [n for n, v in (("DateTime", raw_mod), ("DateTimeOriginal", raw_orig)) if v is None]
        return Check("datetime", title, "not available",
                     f"The file has no {' and no '.join(missing)} tag.")
    mod, orig = parse_exif_datetime(raw_mod), parse_exif_datetime(raw_orig)
    if mod is None or orig is None:
        return Check("datetime", title, "note",
                     f"DateTime {_quoted(raw_mod)} and DateTimeOriginal {_quoted(raw_orig)} are not both valid "
                     "EXIF dates (YYYY:MM:DD HH:MM:SS); blank or malformed dates cannot be compared.")
    delta = (mod - orig).total_seconds()
    exposure = exposure_time_s(info)
    later = tolerance_s + 2 * (exposure or 0.0)
    allowed = (f"{later:.3g} s: {tolerance_s:g} s plus twice the {exposure:.3g} s exposure"
               if exposure is not None and 2 * exposure >= 0.5 else f"{tolerance_s:g} s")
    if delta > later:
        return Check("datetime", title, "suspicious",
                     f"DateTime {raw_mod} is {_duration(delta)} after DateTimeOriginal {raw_orig} (tolerance "
                     f"{allowed}): the file was saved again after capture.")
    if delta < -tolerance_s:
        return Check("datetime", title, "suspicious",
                     f"DateTime {raw_mod} is {_duration(-delta)} before DateTimeOriginal {raw_orig}, which no camera "
                     "writes: one of the two was rewritten.")
    return Check("datetime", title, "consistent",
                 f"DateTime {raw_mod} and DateTimeOriginal {raw_orig} agree within {allowed}.")


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 2 * 3600:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def dimensions(info: EvidenceInfo) -> Check:
    """EXIF PixelXDimension/PixelYDimension against the stored pixel grid.

    A camera records the size it wrote; a swap is consistent with an
    orientation tag of 5 to 8, as a camera that stores rotated pixels may
    record it, and a note otherwise (turned after capture, content
    unchanged). Any other difference means the pixels were resized or
    cropped after capture.
    """
    title = "EXIF pixel dimensions"
    ew, eh = info.exif.exif_image_width, info.exif.exif_image_height
    w, h = info.width, info.height
    if ew is None or eh is None or ew <= 0 or eh <= 0:
        return Check("dimensions", title, "not available",
                     "The file has no valid EXIF PixelXDimension/PixelYDimension.")
    if (ew, eh) == (w, h):
        return Check("dimensions", title, "consistent", f"EXIF records {ew} x {eh} pixels, the stored size.")
    rotated = info.exif.orientation in (5, 6, 7, 8)
    if (ew, eh) == (h, w):
        if rotated:
            return Check("dimensions", title, "consistent",
                         f"EXIF records {ew} x {eh} pixels, the stored {w} x {h} swapped as the orientation tag "
                         f"({info.exif.orientation}) allows.")
        # Viewers and operating systems turn photos losslessly and leave the
        # EXIF size alone: a turn changes no content, so it is a note.
        return Check("dimensions", title, "note",
                     f"EXIF records {ew} x {eh} pixels but the stored grid is {w} x {h}, turned by 90 degrees without "
                     "an orientation tag that explains it: the pixels were rotated after capture, which changes no "
                     "content.")
    same_aspect = abs(ew * h - eh * w) <= max(ew, w)
    how = "resized keeping the aspect ratio (or cropped to the same aspect ratio)" if same_aspect else "cropped"
    return Check("dimensions", title, "suspicious",
                 f"EXIF records {ew} x {eh} pixels but the stored grid is {w} x {h}: the image was {how} after "
                 "capture.")


def dimensions_changed(info: EvidenceInfo) -> bool | None:
    """Whether the EXIF dimensions show a resize or crop (None when EXIF gives none).

    A swap allowed by the orientation tag is no change.
    """
    ew, eh = info.exif.exif_image_width, info.exif.exif_image_height
    if ew is None or eh is None or ew <= 0 or eh <= 0:
        return None
    return (ew, eh) != (info.width, info.height) and (ew, eh) != (info.height, info.width)
