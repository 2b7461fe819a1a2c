"""Checks that need what only ExifTool reads: XMP dates and ancestry, MakerNote serials, embedded previews.

Each reads ``EvidenceInfo.metadata`` (ExifTool's tags by family-1 group) and
reports ``not available`` when the photo was read by the Pillow fallback.
Tag names are ExifTool's (https://exiftool.org/TagNames/).
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from forensics_core import EvidenceInfo

from .checks import Check, _duration, _quoted, parse_exif_datetime

_NEEDS_EXIFTOOL = "Read only with ExifTool, which was not used for this photo (see the evidence section)."
# An XMP date: 2008-05-30T15:56:01[.123][+02:00 | Z]; the time zone is dropped
# because EXIF's DateTimeOriginal (before OffsetTimeOriginal) has none.
_XMP_DATE = re.compile(r"^\s*(\d{4})[:-](\d{2})[:-](\d{2})[ T](\d{2}):(\d{2}):(\d{2})")
_ZONE = re.compile(r"(?:[+-]\d{2}:?\d{2}|Z)\s*$")
_MAKER_GROUPS_EXCLUDED = frozenset({"IFD0", "IFD1", "ExifIFD", "GPS", "InteropIFD", "File", "JFIF", "Composite",
                                    "ICC_Profile", "ICC-header", "Photoshop", "IPTC", "APP14", "MPF0", "FlashPix"})


def _tags(info: EvidenceInfo, name: str, groups: Iterable[str] | None = None) -> list[tuple[str, str]]:
    wanted = None if groups is None else set(groups)
    return [(t.group, t.value) for t in info.metadata
            if t.name == name and (wanted is None or t.group in wanted)]


def _xmp_datetime(text: str):
    m = _XMP_DATE.match(text)
    return None if m is None else parse_exif_datetime("{}:{}:{} {}:{}:{}".format(*m.groups()))


def xmp_dates(info: EvidenceInfo, tolerance_s: float) -> Check:
    """EXIF DateTimeOriginal and CreateDate against their XMP copies (``XMP-exif``, ``XMP-xmp``, ``XMP-photoshop``).

    A program that writes XMP copies the EXIF capture date; a capture date
    that differs between the two was changed in one of them.
    """
    title = "EXIF vs XMP capture dates"
    if not info.metadata:
        return Check("xmp_dates", title, "not available", _NEEDS_EXIFTOOL)
    exif = {n: v for n in ("DateTimeOriginal", "CreateDate") for g, v in _tags(info, n, ["ExifIFD"])}
    xmp = [(g, n, v) for n in ("DateTimeOriginal", "CreateDate", "DateCreated")
           for g, v in _tags(info, n) if g.startswith("XMP-")]
    if not exif or not xmp:
        return Check("xmp_dates", title, "not available",
                     "The file lacks " + ("an EXIF capture date" if not exif else "an XMP capture date") + ".")
    original = parse_exif_datetime(exif.get("DateTimeOriginal") or exif.get("CreateDate"))
    if original is None:
        return Check("xmp_dates", title, "note", "The EXIF capture date is not a valid EXIF date.")
    compared = []
    for group, name, value in xmp:
        when = _xmp_datetime(value)
        if when is None:
            continue
        delta = abs((when - original).total_seconds())
        compared.append(f"{group}:{name} {value}")
        whole_zone = delta <= 14 * 3600 + tolerance_s and min(delta % 900, 900 - delta % 900) <= tolerance_s
        if _ZONE.search(value) and whole_zone:
            compared[-1] += " (a whole time-zone offset from it, which programs that write UTC produce)"
            continue
        if delta > tolerance_s:
            return Check("xmp_dates", title, "suspicious",
                         f"{group}:{name} {value} differs from the EXIF capture date {original:%Y:%m:%d %H:%M:%S} "
                         f"by {_duration(delta)}: one of them was rewritten.")
    if not compared:
        return Check("xmp_dates", title, "note", "The XMP capture dates are not valid dates.")
    return Check("xmp_dates", title, "consistent",
                 f"{'; '.join(compared[:3])} agree with the EXIF capture date {original:%Y:%m:%d %H:%M:%S} "
                 f"within {tolerance_s:g} s.")


def document_ancestors(info: EvidenceInfo) -> Check:
    """``XMP-photoshop:DocumentAncestors``: Photoshop lists there the documents pasted or placed into this one."""
    title = "Documents placed into the file (XMP)"
    if not info.metadata:
        return Check("ancestors", title, "not available", _NEEDS_EXIFTOOL)
    if not any(t.group.startswith("XMP-") for t in info.metadata):
        return Check("ancestors", title, "not available", "The file carries no XMP.")
    found = _tags(info, "DocumentAncestors", ["XMP-photoshop"])
    if not found:
        return Check("ancestors", title, "consistent", "The XMP lists no ancestor documents.")
    entries = [e for e in re.split(r"[;,]\s*|\s+", found[0][1]) if e]
    return Check("ancestors", title, "suspicious",
                 f"photoshop:DocumentAncestors lists {len(entries)} document(s), e.g. {_quoted(entries[0], 60)}: "
                 f"Photoshop records there the documents whose content was pasted or placed into this one.")


def _serial(text: str) -> str:
    return text.strip().lstrip("0").upper()


def makernote_serial(info: EvidenceInfo) -> Check:
    """The body serial number in EXIF (``ExifIFD:SerialNumber``) against the one in the maker's MakerNotes."""
    title = "Serial number: EXIF vs MakerNotes"
    if not info.metadata:
        return Check("serial", title, "not available", _NEEDS_EXIFTOOL)
    exif = _tags(info, "SerialNumber", ["ExifIFD"]) + _tags(info, "BodySerialNumber", ["ExifIFD"])
    maker = [(g, v) for g, v in _tags(info, "SerialNumber") if g not in _MAKER_GROUPS_EXCLUDED
             and not g.startswith("XMP")]
    if not exif or not maker:
        return Check("serial", title, "not available",
                     "The file does not carry a serial number in both EXIF and MakerNotes.")
    a, (group, b) = exif[0][1], maker[0]
    if _serial(str(a)) and _serial(str(b)) and _serial(str(a)) != _serial(str(b)):
        return Check("serial", title, "suspicious",
                     f"EXIF names serial {_quoted(str(a), 40)}, the {group} MakerNotes {_quoted(str(b), 40)}: the "
                     f"two parts of the metadata come from different cameras, or one was rewritten.")
    return Check("serial", title, "consistent", f"EXIF and the {group} MakerNotes name the same serial {_quoted(str(a), 40)}.")


def embedded_previews(info: EvidenceInfo) -> Check:
    """Previews stored besides the EXIF thumbnail (MakerNotes ``PreviewImage``, XMP thumbnails): listed, not compared."""
    title = "Other embedded previews"
    if not info.metadata:
        return Check("previews", title, "not available", _NEEDS_EXIFTOOL)
    names = ("PreviewImage", "JpgFromRaw", "OtherImage", "ThumbnailsImage", "Image")
    found = [f"{t.group}:{t.name}" for t in info.metadata if t.name in names
             and (t.group not in ("IFD0", "IFD1") or t.name != "Image")]
    if not found:
        return Check("previews", title, "not available", "No preview besides the EXIF thumbnail.")
    return Check("previews", title, "note",
                 f"Preview(s) besides the EXIF thumbnail: {', '.join(found[:5])}. Each shows the picture as it was when "
                 "that preview was written; they are listed for the examiner and not compared here.")
