"""Evidence intake: hash the bytes, then decode them, read-only.

The file is read once into memory and hashed before Pillow sees it; nothing
here opens the path for writing. Analysis runs on the stored pixel grid: the
EXIF orientation is recorded, never applied.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import stat
import struct
import sys
import tempfile
import threading
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import datetime, timezone
from functools import cached_property
from pathlib import Path

import numpy as np
from PIL import AvifImagePlugin, ExifTags, Image, ImageFile, TiffImagePlugin, UnidentifiedImageError, features
from PIL import __version__ as _PILLOW_VERSION

from . import exiftool
from .defaults import DEFAULT_MAX_PIXELS
from .text import decoded, visible
from .findings import ContainedImage, EvidenceInfo, ExifSummary, GpsPosition, MetadataTag, RawTag
from .thumbnail import MAX_PIXELS as _THUMBNAIL_MAX_PIXELS
from .thumbnail import EmbeddedThumbnail, read_thumbnail

try:
    import pillow_heif
except ImportError:  # HEIF then reads as "unsupported format"
    pillow_heif = None
else:
    pillow_heif.register_heif_opener()

# Pillow's plugin names; MPO opens through the JPEG plugin. AVIF is Pillow's
# own (libavif), HEIF comes from pillow-heif (libheif).
ALLOWED_FORMATS = ("JPEG", "PNG", "TIFF", "WEBP", "AVIF") + (("HEIF",) if pillow_heif else ())
_RAW_VALUE_LIMIT = 512
#: Frames or pages of a container listed in the findings; the rest are counted as more, not listed.
MAX_LISTED_IMAGES = 100

# Luma weights of ITU-R BT.601, the ones JPEG's YCbCr uses.
_LUMA = np.array([0.299, 0.587, 0.114])


class EvidenceError(Exception):
    """The file cannot be taken in as evidence; the message is one line for the user."""


# Pillow's bomb limit is a module global: every decode of evidence sets it
# under this lock, so threads (batch, Dask) never see each other's limit.
_LIMIT_LOCK = threading.RLock()
_STDERR_LOCK = threading.Lock()
# What Pillow raises on a malformed file, beyond OSError: TIFF headers without
# dimensions give TypeError, bad tag tables KeyError or IndexError.
_DECODE_ERRORS = (OSError, SyntaxError, ValueError, TypeError, KeyError, EOFError, IndexError, struct.error)


@contextmanager
def _c_messages(lines: list[str]):
    """Collect what C decoders (libtiff, libjpeg) print on file descriptor 2 while the block runs.

    They write straight to the process's stderr, past Python; what they say
    about the evidence belongs in its decoder note, not between the one-line
    results on the user's terminal. The lock keeps two threads from swapping
    the descriptor at once.
    """
    with _STDERR_LOCK, tempfile.TemporaryFile() as sink:
        sys.stderr.flush()
        saved = os.dup(2)
        os.dup2(sink.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            lines.extend(line.strip() for line in sink.read(4000).decode("utf-8", "replace").splitlines()
                         if line.strip())


@contextmanager
def _pixel_limit(max_pixels: int):
    with _LIMIT_LOCK:
        previous = Image.MAX_IMAGE_PIXELS
        Image.MAX_IMAGE_PIXELS = max_pixels
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", Image.DecompressionBombWarning)
                yield
        finally:
            Image.MAX_IMAGE_PIXELS = previous


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
    max_pixels : int
        The pixel limit the photo passed at intake (0 when it was not taken
        in by :func:`load_evidence`; :meth:`decoding` then uses the default).
    thumbnail : EmbeddedThumbnail or None
        The EXIF (IFD1) thumbnail, read and decoded once at intake under the
        limits of :mod:`.thumbnail`, or the sentence saying why it cannot be
        read safely; None when the file names none. Consumers use this one
        and never parse ``data`` for it again.
    source : Path or None
        The file as it was read, for files beside it (a C2PA sidecar); None
        for evidence made in memory, whose :attr:`path` is then
        ``info.path``. ``info`` records the path as text
        (:func:`~forensics_core.text.decoded`), which differs from it only
        where the name holds bytes that are not UTF-8.
    """

    info: EvidenceInfo
    data: bytes
    pixels: np.ndarray
    max_pixels: int = 0
    thumbnail: EmbeddedThumbnail | None = None
    source: Path | None = None

    @property
    def path(self) -> Path:
        return self.source if self.source is not None else Path(self.info.path)

    def decoding(self):
        """Context manager: Pillow decodes inside it under this evidence's pixel limit.

        The limit is the one the photo passed at intake (``--max-pixels``),
        so a detector decoding the evidence again, or an image of the same
        size made from it, neither fails on Pillow's own default limit nor
        escapes the user's.
        """
        return _pixel_limit(self.max_pixels or max(DEFAULT_MAX_PIXELS, self.info.width * self.info.height))

    def open_image(self, formats: tuple[str, ...] | None = None) -> Image.Image:
        """Decode the evidence bytes again with Pillow, under the intake's pixel limit.

        For detectors that need a decoder's own view (a JPEG's Y channel, its
        quantisation tables) rather than :attr:`pixels`. The caller closes
        the image (``with evidence.open_image() as img:``). Raises what
        ``PIL.Image.open`` raises for ``formats`` the file is not.
        """
        with self.decoding():
            img = Image.open(io.BytesIO(self.data), formats=formats)
            img.load()
            return img

    @cached_property
    def luma(self) -> np.ndarray:
        """Luma of the stored grid, shape ``(H, W)``, float64 scaled to [0, 1].

        Colour images use BT.601 weights; alpha is ignored; 16-bit and float
        grids are scaled by their type's range (float grids are taken as is,
        except values that are not finite numbers, read as 0 and stated in
        ``info.decoder_note``).
        """
        px = self.pixels
        scale = {"uint8": 255.0, "uint16": 65535.0, "int32": 65535.0}.get(px.dtype.name, 1.0)
        out = np.empty(px.shape[:2], dtype=np.float64)
        # By bands of rows: converting a whole 100 MP colour grid to float64
        # before the weighted sum would hold 2.4 GB of temporaries.
        rows = max(1, (1 << 20) // max(1, px.shape[1]))
        for top in range(0, px.shape[0], rows):
            band = px[top:top + rows]
            if band.ndim == 3:
                band = band[..., :3] @ _LUMA if band.shape[2] >= 3 else band[..., 0]
            np.divide(band, scale, out=out[top:top + rows], casting="unsafe")
        if not np.isfinite(out).all():
            out = np.nan_to_num(out, nan=0.0, posinf=0.0, neginf=0.0)
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

    Strings keep their characters except controls and format characters
    (including the bidirectional overrides that make ``exe.jpg`` read as
    ``gpj.exe``), which are escaped so a terminal or a report shows them
    instead of acting on them; bytes that are not printable ASCII are shown in
    hex. Pillow decodes EXIF text as Latin-1; text that is valid UTF-8 (what
    phones and most programs write) is decoded as UTF-8 instead. Markup in
    strings stays as text here: escaping for HTML is the renderer's job.
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
    elif isinstance(value, str):
        text = _utf8(value)
    elif isinstance(value, (list, dict)):
        text = "; ".join(_safe_text(v) for v in value) if isinstance(value, list) else json.dumps(value, ensure_ascii=False)
    else:
        text = str(value)
    text = text.rstrip("\x00")
    text = visible(text)
    if len(text) > _RAW_VALUE_LIMIT:
        text = text[:_RAW_VALUE_LIMIT] + f"... ({len(text)} characters)"
    return text


def _utf8(text: str) -> str:
    """``text`` re-read as UTF-8 when it is UTF-8 bytes that were decoded as Latin-1, else unchanged."""
    if text.isascii():
        return text
    try:
        return text.encode("latin-1").decode("utf-8")
    except (UnicodeEncodeError, UnicodeDecodeError):
        return text


def _metadata(reading: exiftool.Reading) -> tuple[list[MetadataTag], str]:
    """ExifTool's tags of the evidence, and the sentence naming the reader (or why Pillow's EXIF is all there is)."""
    found = reading.result()
    if found.error is not None:
        return [], (f"Pillow {_PILLOW_VERSION}, EXIF only (no MakerNotes, IPTC or ICC tags, little XMP): "
                    f"{found.error}")
    tags = [MetadataTag(t.group, t.name, _safe_text(t.value)) for t in found.tags]
    return tags, f"ExifTool {found.version} ({' '.join(exiftool.ARGUMENTS)}), reading the hashed bytes"


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


def _read_exif(img: Image.Image, thumbnail_present: bool) -> ExifSummary:
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

    ifd0, sub = ifds["IFD0"], ifds["Exif"]
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
        thumbnail_present=thumbnail_present,
        raw=raw,
    )


def _too_many_pixels(max_pixels: int) -> str:
    return f"exceeds the pixel limit of {max_pixels:,} pixels (possible decompression bomb; see --max-pixels)"


def _open_checked(data: bytes, max_pixels: int) -> tuple[Image.Image, list[ContainedImage]]:
    """Open and fully decode ``data``, refusing bombs, truncation and unlisted formats."""
    # Pillow warns (not fails) between MAX_IMAGE_PIXELS and twice that; the
    # limit is checked here on the header, before any pixel is decoded.
    with _pixel_limit(max_pixels):
        try:
            img = Image.open(io.BytesIO(data), formats=ALLOWED_FORMATS)
        except UnidentifiedImageError:
            _refuse_unreadable_avif(data)
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
        others = _other_images(img, max_pixels)
        img.load()
        return img, others


def _avif_brands(data: bytes) -> set[bytes]:
    """The major and compatible brands of an ISO-BMFF ``ftyp`` box at the start of ``data`` naming AVIF."""
    if len(data) < 16 or data[4:8] != b"ftyp":
        return set()
    size = min(struct.unpack(">I", data[:4])[0], len(data), 4096)
    brands = {data[8:12]} | {data[i:i + 4] for i in range(16, size - 3, 4)}
    return brands & {b"avif", b"avis"}


def _refuse_unreadable_avif(data: bytes) -> None:
    """Refuse, with the decoder's reason, an AVIF that Pillow could not identify; return for anything else.

    Pillow reports every AVIF that libavif refuses as "cannot identify", which
    would call a photo from an early encoder "not an image"; libavif's own
    message is the one the examiner needs.
    """
    if not _avif_brands(data) or not features.check("avif"):
        return
    try:
        AvifImagePlugin.AvifImageFile(io.BytesIO(data)).close()
    except (SyntaxError, ValueError, RuntimeError, OSError) as exc:
        reason = _safe_text(str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
        raise EvidenceError(
            f"an AVIF file its decoder refuses (libavif {features.version('avif')}: {reason}); files from some "
            f"early AVIF encoders break rules of the container that today's decoders enforce, and it is not "
            f"analysed") from None


def _mpo_kind(img: Image.Image, index: int) -> str:
    entries = (getattr(img, "mpinfo", None) or {}).get(0xB002) or []
    if index < len(entries):
        kind = (entries[index].get("Attribute") or {}).get("MPType")
        if kind:
            return f"MPO {str(kind).lower()}"
    return "MPO image"


def _first_pages(img: Image.Image, limit: int) -> int:
    """How many pages the image has, counted up to ``limit``; leaves it on page 0."""
    count = 1
    while count < limit:
        try:
            img.seek(count)
        except EOFError:
            break
        count += 1
    img.seek(0)
    return count


def _other_images(img: Image.Image, max_pixels: int) -> list[ContainedImage]:
    """Every image in the container but the one analysed; leaves ``img`` on the analysed frame.

    The analysed image is the container's primary one: frame 0, or for HEIF
    the image the file marks primary. Frames and pages larger than the pixel
    limit are listed, never decoded.
    """
    out: list[ContainedImage] = []
    kind = {"TIFF": "page", "HEIF": "HEIF image", "AVIF": "AVIF image"}.get(str(img.format), "frame")
    try:
        # A TIFF's page count is found by reading every page's header: 100,000 pages took minutes, before any
        # time limit, so its pages are walked only as far as they are listed.
        n = _first_pages(img, MAX_LISTED_IMAGES + 1) if img.format == "TIFF" else int(getattr(img, "n_frames", 1) or 1)
    except _DECODE_ERRORS:
        # A broken later page must not cost the first one.
        img.seek(0)
        return [ContainedImage(1, f"unreadable {kind}(s) after the first")]
    primary = 0
    unlisted = n > MAX_LISTED_IMAGES
    n = min(n, MAX_LISTED_IMAGES)
    if n > 1:
        for i in range(n):
            try:
                img.seek(i)
            except _DECODE_ERRORS:
                out.append(ContainedImage(i, f"unreadable {kind}"))
                continue
            if img.format == "HEIF" and img.info.get("primary"):
                primary = i
            out.append(ContainedImage(i, _mpo_kind(img, i) if img.format == "MPO" else kind, *img.size))
        img.seek(primary)
        out = [c for c in out if c.index != primary]
    if unlisted:
        out.append(ContainedImage(MAX_LISTED_IMAGES, f"more {kind}s, not listed (over {MAX_LISTED_IMAGES} in all)"))
    if img.format == "HEIF":
        for key, kind in (("thumbnails", "HEIF thumbnail"), ("depth_images", "HEIF depth image")):
            for i, item in enumerate(img.info.get(key) or []):
                size = getattr(item, "size", None) or (item if isinstance(item, tuple) else (None, None))
                out.append(ContainedImage(i, kind, *(int(v) if v else None for v in size[:2])))
        for i, name in enumerate(img.info.get("aux") or {}):
            out.append(ContainedImage(i, f"HEIF auxiliary image ({name})"))
    return out


def _decoder_note(img: Image.Image, orientation: int | None) -> str | None:
    if img.format == "HEIF" and img.info.get("original_orientation") not in (None, 1):
        return (f"libheif applies a HEIF file's rotation and mirror properties when it decodes; the EXIF orientation "
                f"was {img.info['original_orientation']} and the analysed grid is the image as displayed")
    if img.format == "AVIF" and orientation not in (None, 1):
        # Pillow's AVIF decoder leaves the grid as stored and reports the
        # container's irot/imir properties as the EXIF orientation, over any
        # orientation the file's EXIF holds.
        return (f"the AVIF decoder reports the file's rotation and mirror properties (irot, imir) as orientation "
                f"{orientation}, in place of any EXIF orientation; the analysed grid is the image as stored, "
                f"before that rotation, and a viewer displays it rotated")
    return None


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
        With a one-line reason: missing path, a path that cannot be read (a
        link that loops, with the system's words), a directory, an empty
        file, bytes that are no image, an unsupported format, a truncated or
        corrupt image, or too many pixels.

    Examples
    --------
    >>> from forensics_core import load_evidence
    >>> evidence = load_evidence("tests/data/calibration/left01.jpg")
    >>> evidence.info.format, evidence.pixels.shape, evidence.info.sha256[:12]
    ('JPEG', (480, 640), '9621899098ad')
    """
    p = Path(path)
    try:
        mode = p.stat().st_mode
    except (FileNotFoundError, ValueError):  # ValueError: a name with a NUL byte, which no file has
        raise EvidenceError("no such file") from None
    except OSError as exc:
        # A link that loops, a folder that may not be entered, a name too long:
        # the file may well exist, so the reason is given as the system states it.
        raise EvidenceError(f"cannot read: {exc.strerror or exc}") from None
    if stat.S_ISDIR(mode):
        raise EvidenceError("is a directory, not a photo")
    if not stat.S_ISREG(mode):
        raise EvidenceError("is not a regular file")
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise EvidenceError(f"cannot read: {exc.strerror or exc}") from None
    sha256, sha512, md5 = _hashes(data)
    hashed_at = datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")
    if not data:
        raise EvidenceError("empty file")
    # ExifTool starts on another core while Pillow decodes; a photo the
    # intake refuses stops it.
    reading = exiftool.start(data)
    try:
        # Pillow warns about what it tolerates in a file (EXIF offsets out of
        # range, truncated tags); those are observations about the evidence, kept
        # in the decoder note, not lines on the user's terminal.
        printed: list[str] = []
        with warnings.catch_warnings(record=True) as caught, _c_messages(printed):
            warnings.simplefilter("always")
            try:
                img, others = _open_checked(data, max_pixels)
            except EvidenceError:
                raise
            except UnidentifiedImageError:
                raise EvidenceError("not an image (no known image format recognised)") from None
            except (Image.DecompressionBombError, Image.DecompressionBombWarning):
                raise EvidenceError(_too_many_pixels(max_pixels)) from None
            except _DECODE_ERRORS as exc:
                reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                raise EvidenceError(f"corrupt or truncated image: {reason}") from None

            # Once, here: the metadata check, its figure and the report all use
            # this reading. The limit is Pillow's global, so it is held under the
            # intake's lock; a non-JPEG's EXIF is found by opening the file again.
            with _pixel_limit(max(max_pixels, _THUMBNAIL_MAX_PIXELS)):
                thumbnail = read_thumbnail(data, str(img.format))
            try:
                exif = _read_exif(img, thumbnail is not None and thumbnail.named)
            except (SyntaxError, ValueError, TypeError, KeyError, IndexError, OSError, EOFError, struct.error,
                    ZeroDivisionError, RecursionError) as exc:
                # Broken EXIF is an observation about the file, not a reason to stop.
                reason = str(exc).splitlines()[0][:200] if str(exc) else type(exc).__name__
                exif = ExifSummary(unreadable=f"EXIF unreadable: {_safe_text(reason)}")
        quant = getattr(img, "quantization", None) or {}
        fmt, (width, height), mode = str(img.format), img.size, img.mode
        icc_profile = bool(img.info.get("icc_profile"))
        notes = [_decoder_note(img, exif.orientation)]
        with warnings.catch_warnings(record=True) as decoding, _c_messages(printed):
            warnings.simplefilter("always")
            try:
                pixels = _pixel_array(img)
            finally:
                img.close()
    except BaseException:
        reading.cancel()
        raise
    metadata, metadata_reader = _metadata(reading)
    tolerated = sorted({_safe_text(str(w.message)) for w in caught + decoding} | {_safe_text(t) for t in printed})[:5]
    if tolerated:
        notes.append("The decoder tolerated: " + "; ".join(tolerated) + ".")
    if pixels.dtype.kind == "f" and not np.isfinite(pixels).all():
        bad = int(pixels.size - np.isfinite(pixels).sum())
        notes.append(f"{bad:,} sample(s) of the stored grid are not finite numbers (NaN or infinite); the detectors "
                     f"read them as 0.")
    source = p.resolve()
    info = EvidenceInfo(
        path=decoded(str(source)),
        name=decoded(p.name),
        size=len(data),
        sha256=sha256,
        sha512=sha512,
        md5=md5,
        hashed_at=hashed_at,
        format=fmt,
        width=width,
        height=height,
        mode=mode,
        orientation=exif.orientation,
        icc_profile=icc_profile,
        quantization_tables={str(k): [int(v) for v in table] for k, table in sorted(quant.items())},
        exif=exif,
        other_images=others,
        decoder_note=" ".join(n for n in notes if n) or None,
        metadata=metadata,
        metadata_reader=metadata_reader,
    )
    return Evidence(info=info, data=data, pixels=pixels, max_pixels=max_pixels, thumbnail=thumbnail, source=source)
