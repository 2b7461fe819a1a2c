"""Evidence intake: hash the bytes, then decode them, read-only.

The file is read once into memory and hashed before Pillow sees it; nothing
here opens the path for writing. Analysis runs on the stored pixel grid: the
EXIF orientation is recorded, never applied.
"""

from __future__ import annotations

import hashlib
import io
import os
import struct
import warnings
from dataclasses import dataclass
from datetime import datetime, timezone
from functools import cached_property
from pathlib import Path

import numpy as np
from PIL import ExifTags, Image, ImageFile, TiffImagePlugin, UnidentifiedImageError

from .findings import EvidenceInfo, ExifSummary, GpsPosition, RawTag

ALLOWED_FORMATS = ("JPEG", "PNG", "TIFF")
DEFAULT_MAX_PIXELS = 150_000_000
_RAW_VALUE_LIMIT = 512

# Luma weights of ITU-R BT.601, the ones JPEG's YCbCr uses.
_LUMA = np.array([0.299, 0.587, 0.114])


class EvidenceError(Exception):
    """The file cannot be taken in as evidence; the message is one line for the user."""


@dataclass(frozen=True, eq=False)
class Evidence:
    """A photo taken in as evidence.

    Attributes
    ----------
    info : EvidenceInfo
        Identity (hashes taken before decoding) and properties, as recorded
        in the findings.
    data : bytes
        The file's original bytes, exactly as read (for detectors that parse
        the container, e.g. JPEG markers).
    pixels : numpy.ndarray
        The decoded stored grid, read-only, shape ``(H, W)`` for one channel or
        ``(H, W, C)``; dtype as stored (``uint8``, ``uint16``, ``int32`` or
        ``float32``). Orientation is not applied.
    """

    info: EvidenceInfo
    data: bytes
    pixels: np.ndarray

    @property
    def path(self) -> Path:
        return Path(self.info.path)

    @cached_property
    def luma(self) -> np.ndarray:
        """Luma of the stored grid, shape ``(H, W)``, float64 scaled to [0, 1].

        Colour images use BT.601 weights; alpha is ignored; 16-bit and float
        grids are scaled by their type's range (float grids are taken as is).
        """
        px = self.pixels
        if px.ndim == 3:
            px = px[..., :3] @ _LUMA[: min(3, px.shape[2])] if px.shape[2] >= 3 else px[..., 0]
        px = np.asarray(px, dtype=np.float64)
        scale = {"uint8": 255.0, "uint16": 65535.0, "int32": 65535.0}.get(self.pixels.dtype.name, 1.0)
        out = px / scale
        out.flags.writeable = False
        return out


def _hashes(data: bytes) -> tuple[str, str, str]:
    return (
        hashlib.sha256(data).hexdigest(),
        hashlib.sha512(data).hexdigest(),
        hashlib.md5(data, usedforsecurity=False).hexdigest(),
    )


def _safe_text(value: object) -> str:
    """Render an EXIF value as printable text of bounded length.

    Strings keep their characters except controls, which are escaped so a
    terminal or a report shows them instead of acting on them; bytes that are
    not printable ASCII are shown in hex. Markup in strings stays as text here:
    escaping for HTML is the renderer's job.
    """
    if isinstance(value, bytes):
        stripped = value.rstrip(b"\x00")
        if stripped and all(32 <= b < 127 for b in stripped):
            text = stripped.decode("ascii")
        else:
            text = "0x" + value[: _RAW_VALUE_LIMIT // 2].hex()
            if len(value) > _RAW_VALUE_LIMIT // 2:
                text += f"... ({len(value)} bytes)"
            return text
    elif isinstance(value, tuple):
        text = "(" + ", ".join(_safe_text(v) for v in value) + ")"
    elif isinstance(value, TiffImagePlugin.IFDRational):
        text = "nan" if value.denominator == 0 else f"{float(value):g}"
    else:
        text = str(value)
    text = text.rstrip("\x00")
    text = "".join(c if c.isprintable() else f"\\x{ord(c):02x}" for c in text)
    if len(text) > _RAW_VALUE_LIMIT:
        text = text[:_RAW_VALUE_LIMIT] + f"... ({len(text)} characters)"
    return text


def _clean_str(value: object) -> str | None:
    if value is None:
        return None
    text = _safe_text(value).strip()
    return text or None


def _number(value: object) -> float | None:
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, ZeroDivisionError):
        return None
    return number if np.isfinite(number) else None


def _int(value: object) -> int | None:
    number = _number(value)
    return int(number) if number is not None else None


def _dms_to_degrees(dms: object, ref: object) -> float | None:
    if not isinstance(dms, tuple) or len(dms) != 3:
        return None
    parts = [_number(v) for v in dms]
    if any(p is None for p in parts):
        return None
    deg = parts[0] + parts[1] / 60.0 + parts[2] / 3600.0  # type: ignore[operator]
    return -deg if str(ref).strip().upper() in ("S", "W") else deg


def _gps(gps_ifd: dict) -> GpsPosition | None:
    lat = _dms_to_degrees(gps_ifd.get(2), gps_ifd.get(1))
    lon = _dms_to_degrees(gps_ifd.get(4), gps_ifd.get(3))
    alt = _number(gps_ifd.get(6))
    if alt is not None and gps_ifd.get(5) in (1, b"\x01"):
        alt = -alt
    if lat is None and lon is None and alt is None:
        return None
    return GpsPosition(latitude=lat, longitude=lon, altitude_m=alt)


def _read_exif(img: Image.Image) -> ExifSummary:
    exif = img.getexif()
    ifds = {
        "IFD0": dict(exif),
        "Exif": dict(exif.get_ifd(ExifTags.IFD.Exif)),
        "GPS": dict(exif.get_ifd(ExifTags.IFD.GPSInfo)),
        "Interop": dict(exif.get_ifd(ExifTags.IFD.Interop)),
        "IFD1": dict(exif.get_ifd(ExifTags.IFD.IFD1)),
    }
    raw = []
    for ifd_name, tags in ifds.items():
        names = ExifTags.GPSTAGS if ifd_name == "GPS" else ExifTags.TAGS
        for tag in sorted(tags):
            if ifd_name == "IFD0" and tag in (ExifTags.IFD.Exif, ExifTags.IFD.GPSInfo, ExifTags.IFD.Interop):
                continue
            raw.append(RawTag(ifd=ifd_name, tag=int(tag), name=names.get(tag, f"0x{tag:04x}"), value=_safe_text(tags[tag])))

    ifd0, sub, ifd1 = ifds["IFD0"], ifds["Exif"], ifds["IFD1"]
    tag = ExifTags.Base
    return ExifSummary(
        make=_clean_str(ifd0.get(tag.Make)),
        model=_clean_str(ifd0.get(tag.Model)),
        lens_make=_clean_str(sub.get(tag.LensMake)),
        lens_model=_clean_str(sub.get(tag.LensModel)),
        focal_length_mm=_number(sub.get(tag.FocalLength)),
        focal_length_35mm=_number(sub.get(tag.FocalLengthIn35mmFilm)),
        datetime=_clean_str(ifd0.get(tag.DateTime)),
        datetime_original=_clean_str(sub.get(tag.DateTimeOriginal)),
        software=_clean_str(ifd0.get(tag.Software)),
        orientation=_int(ifd0.get(tag.Orientation)),
        exif_image_width=_int(sub.get(tag.ExifImageWidth)),
        exif_image_height=_int(sub.get(tag.ExifImageHeight)),
        gps=_gps(ifds["GPS"]),
        thumbnail_present=bool(ifd1.get(tag.JpegIFOffset)) and bool(ifd1.get(tag.JpegIFByteCount)),
        raw=raw,
    )


def _too_many_pixels(max_pixels: int) -> str:
    return f"exceeds the pixel limit of {max_pixels:,} pixels (possible decompression bomb; see --max-pixels)"


def _open_checked(data: bytes, max_pixels: int) -> Image.Image:
    """Open and fully decode ``data``, refusing bombs, truncation and unlisted formats."""
    # Pillow warns (not fails) between MAX_IMAGE_PIXELS and twice that; the
    # limit is checked here on the header, before any pixel is decoded.
    previous = Image.MAX_IMAGE_PIXELS
    Image.MAX_IMAGE_PIXELS = max_pixels
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            try:
                img = Image.open(io.BytesIO(data), formats=ALLOWED_FORMATS)
            except UnidentifiedImageError:
                with Image.open(io.BytesIO(data)) as probe:
                    fmt = probe.format
                raise EvidenceError(
                    f"unsupported format {fmt}; allowed: {', '.join(ALLOWED_FORMATS)}"
                ) from None
            w, h = img.size
            if w * h > max_pixels:
                raise EvidenceError(f"{w}x{h}: " + _too_many_pixels(max_pixels))
            if ImageFile.LOAD_TRUNCATED_IMAGES:
                raise EvidenceError("refusing to run with Pillow's LOAD_TRUNCATED_IMAGES enabled")
            img.load()
            return img
    finally:
        Image.MAX_IMAGE_PIXELS = previous


def _pixel_array(img: Image.Image) -> np.ndarray:
    if img.mode in ("P", "PA"):
        img = img.convert("RGBA" if "transparency" in img.info or img.mode == "PA" else "RGB")
    elif img.mode in ("1", "CMYK", "YCbCr", "LAB", "HSV"):
        img = img.convert("L" if img.mode == "1" else "RGB")
    elif img.mode.startswith("I;16"):
        img = img.convert("I")
    arr = np.array(img)
    if arr.dtype == np.int32 and arr.min(initial=0) >= 0 and arr.max(initial=0) <= 65535:
        arr = arr.astype(np.uint16)
    arr.flags.writeable = False
    return arr


def load_evidence(path: str | os.PathLike[str], *, max_pixels: int = DEFAULT_MAX_PIXELS) -> Evidence:
    """Take in one photo as evidence.

    Parameters
    ----------
    path : path-like
        The evidence file. It is read, never written.
    max_pixels : int
        Largest pixel count accepted; larger images are refused as possible
        decompression bombs.

    Returns
    -------
    Evidence

    Raises
    ------
    EvidenceError
        With a one-line reason: missing path, a directory, an empty file,
        bytes that are no image, an unsupported format, a truncated or corrupt
        image, or too many pixels.
    """
    p = Path(path)
    if not p.exists():
        raise EvidenceError("no such file")
    if p.is_dir():
        raise EvidenceError("is a directory, not a photo")
    if not p.is_file():
        raise EvidenceError("is not a regular file")
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise EvidenceError(f"cannot read: {exc.strerror or exc}") from None
    sha256, sha512, md5 = _hashes(data)
    hashed_at = datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")
    if not data:
        raise EvidenceError("empty file")
    try:
        img = _open_checked(data, max_pixels)
    except EvidenceError:
        raise
    except UnidentifiedImageError:
        raise EvidenceError("not an image (no known image format recognised)") from None
    except (Image.DecompressionBombError, Image.DecompressionBombWarning):
        raise EvidenceError(_too_many_pixels(max_pixels)) from None
    except (OSError, SyntaxError, ValueError, EOFError, IndexError, struct.error) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise EvidenceError(f"corrupt or truncated image: {reason}") from None

    exif = _read_exif(img)
    quant = getattr(img, "quantization", None) or {}
    info = EvidenceInfo(
        path=str(p.resolve()),
        name=p.name,
        size=len(data),
        sha256=sha256,
        sha512=sha512,
        md5=md5,
        hashed_at=hashed_at,
        format=str(img.format),
        width=img.size[0],
        height=img.size[1],
        mode=img.mode,
        orientation=exif.orientation,
        icc_profile=bool(img.info.get("icc_profile")),
        quantization_tables={str(k): [int(v) for v in table] for k, table in sorted(quant.items())},
        exif=exif,
    )
    try:
        pixels = _pixel_array(img)
    finally:
        img.close()
    return Evidence(info=info, data=data, pixels=pixels)
