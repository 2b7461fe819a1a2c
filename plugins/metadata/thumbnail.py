"""The embedded EXIF thumbnail (IFD1) against the stored image.

A camera writes a small JPEG of the picture into the EXIF block (IFD1, tags
JPEGInterchangeFormat 0x0201 and JPEGInterchangeFormatLength 0x0202, offsets
counted from the TIFF header; Exif 2.32). Many editors change the pixels but
copy the EXIF block unchanged, so the thumbnail keeps showing the picture as
it was: a thumbnail that does not match the image is a classic sign of
editing (Kee & Farid 2010 study thumbnails as forensic evidence; editors
that do regenerate the thumbnail leave one that matches, which this check
cannot tell from the camera's).

Stages: find the EXIF block in the file (:func:`exif_block`), walk the TIFF
structure to IFD1 with every offset bounds-checked (:func:`thumbnail_bytes`),
decode the thumbnail under a size and pixel limit (:func:`decode`), locate its
picture area (cameras letterbox a 3:2 picture into a 4:3 thumbnail with black
bands; :func:`content_box`), and compare it with the stored image reduced to
the same size (:func:`compare`). Neither the thumbnail nor the image has the
orientation tag applied: both are stored in the sensor's frame.
"""

from __future__ import annotations

import io
import math
import struct
import warnings
from dataclasses import dataclass

import numpy as np
from PIL import Image
from scipy import ndimage

from .checks import Check

_EXIF_HEADER = b"Exif\x00\x00"
_MAX_IFD_ENTRIES = 1024
_TAG_JPEG_OFFSET, _TAG_JPEG_LENGTH = 0x0201, 0x0202
# Bands a camera fills to letterbox the picture: nearly uniform (luma standard
# deviation below this, on a [0, 1] scale) once the row or column next to the
# picture, which JPEG ringing touches, is left out.
_BAND_MAX_STD = 0.04
_BAND_MIN_PX = 2


class ThumbnailError(ValueError):
    """The file's thumbnail data is malformed; the message says how, in one sentence."""


@dataclass(frozen=True)
class Comparison:
    """The thumbnail against the image reduced to its picture area.

    Attributes
    ----------
    box : tuple of int
        Picture area in the thumbnail, ``(x0, y0, x1, y1)`` pixels, end exclusive.
    aspect_image, aspect_thumbnail : float
        Width / height of the stored image and of the thumbnail's picture area.
    aspect_difference : float
        ``|ln(aspect_thumbnail / aspect_image)|``.
    aspect_tolerance : float
        Allowed ``aspect_difference``: the parameter plus the rounding of a
        picture area this small (1.5 px on its shorter side).
    rotated : bool
        The thumbnail's aspect matches the image turned by 90 degrees instead.
    correlation : float or None
        Pearson correlation of the two lumas (None when the aspect differs).
    correlation_outside : float or None
        The same outside the largest differing region (and its blur margin):
        high when the rest of the picture matches, i.e. the difference is local.
    gain, offset : float or None
        Least-squares fit ``thumbnail = gain * image + offset`` (lumas in [0, 1]).
    psnr_db : float or None
        PSNR of the thumbnail against the fitted image, dB.
    changed_fraction : float or None
        Share of the picture area whose residual exceeds the change threshold.
    region_fraction : float or None
        Share of the picture area covered by the largest connected changed region.
    changed_box : tuple of int or None
        Bounding box, thumbnail pixels (end exclusive), of the largest changed region.
    difference : ndarray or None, shape (h, w)
        Absolute residual of the blurred lumas, luma units; for the report's figure.
    """

    box: tuple[int, int, int, int]
    aspect_image: float
    aspect_thumbnail: float
    aspect_difference: float
    aspect_tolerance: float
    rotated: bool
    correlation: float | None = None
    correlation_outside: float | None = None
    gain: float | None = None
    offset: float | None = None
    psnr_db: float | None = None
    changed_fraction: float | None = None
    region_fraction: float | None = None
    changed_box: tuple[int, int, int, int] | None = None
    difference: np.ndarray | None = None


def exif_block(data: bytes, file_format: str) -> bytes | None:
    """The TIFF structure of the file's EXIF, without the ``Exif\\0\\0`` header.

    For a JPEG the marker segments before the first scan are walked and the
    first APP1 segment holding EXIF is returned; for other formats Pillow's
    reading of the EXIF chunk is used.

    Raises
    ------
    ThumbnailError
        When a JPEG marker segment runs past the end of the file.
    """
    if file_format != "JPEG":
        try:
            with Image.open(io.BytesIO(data)) as img:
                raw = img.info.get("exif")
        except (OSError, ValueError, SyntaxError, EOFError):
            return None
        if not raw:
            return None
        return raw[len(_EXIF_HEADER):] if raw.startswith(_EXIF_HEADER) else raw
    if data[:2] != b"\xff\xd8":
        raise ThumbnailError("the file does not start with a JPEG SOI marker")
    i = 2
    while i + 4 <= len(data):
        if data[i] != 0xFF:
            raise ThumbnailError(f"no JPEG marker at byte {i} where one was expected")
        marker = data[i + 1]
        if marker == 0xFF:
            i += 1
            continue
        if marker == 0x01 or 0xD0 <= marker <= 0xD8:
            i += 2
            continue
        if marker in (0xDA, 0xD9):
            return None
        length = int.from_bytes(data[i + 2:i + 4], "big")
        if length < 2 or i + 2 + length > len(data):
            raise ThumbnailError(f"JPEG marker segment 0xFF{marker:02X} at byte {i} claims {length} bytes, "
                                 "past the end of the file")
        if marker == 0xE1 and data[i + 4:i + 4 + len(_EXIF_HEADER)] == _EXIF_HEADER:
            return data[i + 4 + len(_EXIF_HEADER):i + 2 + length]
        i += 2 + length
    return None


def _read_ifd(tiff: bytes, offset: int, endian: str) -> tuple[dict[int, tuple[int, int, bytes]], int]:
    """Entries ``tag -> (type, count, 4-byte value field)`` of the IFD at ``offset``, and the next IFD's offset."""
    if offset < 8 or offset + 2 > len(tiff):
        raise ThumbnailError(f"an IFD offset ({offset}) points outside the {len(tiff)}-byte EXIF block")
    (n,) = struct.unpack_from(endian + "H", tiff, offset)
    end = offset + 2 + 12 * n
    if n > _MAX_IFD_ENTRIES or end + 4 > len(tiff):
        raise ThumbnailError(f"the IFD at offset {offset} claims {n} entries, more than the EXIF block holds")
    entries = {}
    for k in range(n):
        tag, typ, count = struct.unpack_from(endian + "HHI", tiff, offset + 2 + 12 * k)
        entries[tag] = (typ, count, tiff[offset + 10 + 12 * k:offset + 14 + 12 * k])
    (next_offset,) = struct.unpack_from(endian + "I", tiff, end)
    return entries, next_offset


def _scalar(entry: tuple[int, int, bytes] | None, endian: str) -> int | None:
    """A SHORT or LONG entry with one value, or None."""
    if entry is None or entry[1] != 1:
        return None
    typ, _, field = entry
    if typ == 3:
        return struct.unpack_from(endian + "H", field)[0]
    if typ == 4:
        return struct.unpack_from(endian + "I", field)[0]
    return None


def thumbnail_bytes(tiff: bytes, max_bytes: int) -> bytes | None:
    """The JPEG thumbnail that IFD1 points to.

    None when there is no IFD1 or it names no JPEG thumbnail; empty bytes when
    it names one of length 0 (software that drops the thumbnail may leave that).

    Parameters
    ----------
    tiff : bytes
        The EXIF TIFF structure (from :func:`exif_block`).
    max_bytes : int
        Larger thumbnails are refused: the standard limits them to 64 kB.

    Raises
    ------
    ThumbnailError
        On a malformed header or IFD, offsets outside the block, an oversized
        thumbnail or one that is not a JPEG stream.
    """
    if len(tiff) < 8 or tiff[:2] not in (b"II", b"MM"):
        raise ThumbnailError("the EXIF block has no valid TIFF header")
    endian = "<" if tiff[:2] == b"II" else ">"
    magic, ifd0 = struct.unpack_from(endian + "HI", tiff, 2)
    if magic != 42:
        raise ThumbnailError("the EXIF block has no valid TIFF header")
    _, ifd1 = _read_ifd(tiff, ifd0, endian)
    if ifd1 == 0:
        return None
    entries, _ = _read_ifd(tiff, ifd1, endian)
    offset = _scalar(entries.get(_TAG_JPEG_OFFSET), endian)
    length = _scalar(entries.get(_TAG_JPEG_LENGTH), endian)
    if offset is None and length is None:
        return None
    if offset is None or length is None:
        raise ThumbnailError("IFD1 gives the thumbnail's offset or length but not both")
    if length == 0:
        return b""
    if length > max_bytes:
        raise ThumbnailError(f"IFD1 claims a {length}-byte thumbnail, more than the {max_bytes} bytes accepted")
    if offset < 8 or offset + length > len(tiff):
        raise ThumbnailError(f"IFD1 places the thumbnail at bytes {offset}-{offset + length}, outside the "
                             f"{len(tiff)}-byte EXIF block")
    blob = tiff[offset:offset + length]
    if blob[:2] != b"\xff\xd8":
        raise ThumbnailError("the bytes IFD1 points to are not a JPEG stream")
    return blob


def decode(blob: bytes, max_pixels: int) -> Image.Image:
    """The thumbnail decoded as RGB, refusing more than ``max_pixels`` pixels.

    Raises
    ------
    ThumbnailError
        When it does not decode or is too large.
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(io.BytesIO(blob), formats=["JPEG"]) as img:
                w, h = img.size
                if w * h > max_pixels or w < 1 or h < 1:
                    raise ThumbnailError(f"the thumbnail claims {w} x {h} pixels, outside the accepted 1 to "
                                         f"{max_pixels}")
                img.load()
                return img.convert("RGB")
    except ThumbnailError:
        raise
    except (OSError, ValueError, SyntaxError, EOFError, struct.error, Image.DecompressionBombWarning,
            Image.DecompressionBombError) as exc:
        raise ThumbnailError(f"the thumbnail does not decode ({type(exc).__name__})") from None


def luma_of(img: Image.Image) -> np.ndarray:
    """BT.601 luma of an RGB or grey Pillow image, float in [0, 1], shape (h, w)."""
    return np.asarray(img.convert("L"), dtype=np.float64) / 255.0


def to_8bit(pixels: np.ndarray) -> np.ndarray:
    """The stored grid as 8-bit grey or RGB, shape (H, W) or (H, W, 3); alpha dropped, 16-bit and float scaled."""
    px = np.asarray(pixels)
    if px.ndim == 3:
        px = px[..., :3] if px.shape[2] >= 3 else px[..., 0]
    if px.dtype == np.uint8:
        return px
    scale = {"uint16": 65535.0, "int32": 65535.0}.get(px.dtype.name, 1.0)
    return np.clip(px.astype(np.float32) / scale * 255.0 + 0.5, 0, 255).astype(np.uint8)


def reduced_image(pixels: np.ndarray, size: tuple[int, int]) -> Image.Image:
    """The stored grid reduced to ``size`` = (w, h), as 8-bit RGB or grey.

    Pillow bins by an integer factor first (``reducing_gap``), so a 12 MP
    photo costs tens of milliseconds, then resamples with Lanczos.
    """
    return Image.fromarray(to_8bit(pixels)).resize(size, Image.Resampling.LANCZOS, reducing_gap=3.0)


def _uniform(band: np.ndarray) -> bool:
    return band.size > 0 and float(band.std()) < _BAND_MAX_STD


def content_box(thumb: np.ndarray, aspect_image: float, tolerance: float) -> tuple[int, int, int, int]:
    """The thumbnail's picture area: all of it, or the part between uniform letterbox bands.

    When the whole thumbnail's aspect differs from the image's by more than
    ``tolerance`` (log ratio), the bands that would make them equal are
    tested: if both are uniform the picture lies between them.

    Parameters
    ----------
    thumb : ndarray, shape (h, w)
        Thumbnail luma.
    aspect_image : float
        Width / height of the stored image.
    tolerance : float
        Log aspect ratio difference treated as equal.

    Returns
    -------
    tuple of int
        ``(x0, y0, x1, y1)``, end exclusive.
    """
    h, w = thumb.shape
    full = (0, 0, w, h)
    if abs(math.log((w / h) / aspect_image)) <= tolerance:
        return full
    if aspect_image > w / h:
        inner = round(w / aspect_image)
        top = (h - inner) // 2
        if top < _BAND_MIN_PX:
            return full
        bottom = top + inner
        if _uniform(thumb[:top - 1]) and _uniform(thumb[bottom + 1:]):
            return (0, top, w, bottom)
        return full
    inner = round(h * aspect_image)
    left = (w - inner) // 2
    if left < _BAND_MIN_PX:
        return full
    right = left + inner
    if _uniform(thumb[:, :left - 1]) and _uniform(thumb[:, right + 1:]):
        return (left, 0, right, h)
    return full


def compare(pixels: np.ndarray, thumb: np.ndarray, aspect_tolerance: float, blur_px: float,
            change_threshold: float) -> Comparison:
    """Compare the thumbnail with the stored image.

    The image is reduced to the thumbnail's picture area and both are blurred
    by a Gaussian of ``blur_px`` thumbnail pixels: cameras decimate their
    thumbnails with little filtering, so fine texture aliases differently in
    the two and must not count. The thumbnail's luma is then fitted as
    ``gain * image + offset`` (cameras render thumbnails with their own tone
    curve), and the absolute residual is thresholded at ``change_threshold``.

    Parameters
    ----------
    pixels : ndarray, shape (H, W) or (H, W, C)
        The evidence's stored grid.
    thumb : ndarray, shape (h, w)
        Thumbnail luma in [0, 1].
    aspect_tolerance : float
        Allowed ``|ln(aspect ratio)|`` difference, before the rounding allowance.
    blur_px : float
        Gaussian standard deviation, thumbnail pixels.
    change_threshold : float
        Residual luma (on [0, 1]) above which a thumbnail pixel counts as changed.
    """
    H, W = pixels.shape[:2]
    aspect_image = W / H
    x0, y0, x1, y1 = box = content_box(thumb, aspect_image, aspect_tolerance + 1.5 / min(thumb.shape))
    w, h = x1 - x0, y1 - y0
    tol = aspect_tolerance + 1.5 / min(w, h)
    diff = abs(math.log((w / h) / aspect_image))
    rotated = abs(math.log((w / h) * aspect_image)) <= tol < diff
    result = Comparison(box, aspect_image, w / h, diff, tol, rotated)
    if diff > tol or min(w, h) < 8:
        return result
    t = ndimage.gaussian_filter(thumb[y0:y1, x0:x1], blur_px, mode="nearest")
    m = ndimage.gaussian_filter(luma_of(reduced_image(pixels, (w, h))), blur_px, mode="nearest")
    sd_t, sd_m = float(t.std()), float(m.std())
    if sd_t < 1e-6 or sd_m < 1e-6:
        return result
    design = np.column_stack([m.ravel(), np.ones(m.size)])
    (gain, offset), *_ = np.linalg.lstsq(design, t.ravel(), rcond=None)
    residual = np.abs(t - (gain * m + offset))
    labels, n = ndimage.label(residual > change_threshold)
    region_fraction, changed_box = 0.0, None
    outside = np.ones_like(residual, dtype=bool)
    if n:
        sizes = np.bincount(labels.ravel())[1:]
        largest = int(np.argmax(sizes))
        sl = ndimage.find_objects(labels)[largest]
        region_fraction = float(sizes[largest]) / residual.size
        changed_box = (sl[1].start + x0, sl[0].start + y0, sl[1].stop + x0, sl[0].stop + y0)
        # The blur spreads the region by about two standard deviations.
        outside = ~ndimage.binary_dilation(labels == largest + 1, iterations=max(1, round(2 * blur_px)))
    correlation = float(np.corrcoef(t.ravel(), m.ravel())[0, 1])
    rest = t[outside], m[outside]
    correlation_outside = (float(np.corrcoef(*rest)[0, 1])
                           if rest[0].size >= 16 and rest[0].std() > 1e-6 and rest[1].std() > 1e-6 else None)
    mse = float(np.mean(residual**2))
    return Comparison(
        box, aspect_image, w / h, diff, tol, rotated,
        correlation=correlation,
        correlation_outside=correlation_outside,
        gain=float(gain),
        offset=float(offset),
        psnr_db=10.0 * math.log10(1.0 / mse) if mse > 1e-12 else 99.0,
        changed_fraction=float((residual > change_threshold).mean()),
        region_fraction=region_fraction,
        changed_box=changed_box,
        difference=residual,
    )


@dataclass(frozen=True)
class ThumbnailThresholds:
    """The thresholds of the thumbnail check (see :data:`..detector.DEFAULT_PARAMS`)."""

    max_bytes: int
    max_pixels: int
    aspect_tolerance: float
    min_correlation: float
    blur_px: float
    change_threshold: float
    max_region_fraction: float


def extract(data: bytes, file_format: str, limits: ThumbnailThresholds) -> Image.Image | None:
    """The decoded thumbnail, or None when the file has none.

    Raises
    ------
    ThumbnailError
        When the file names a thumbnail that cannot be read safely.
    """
    tiff = exif_block(data, file_format)
    if tiff is None:
        return None
    blob = thumbnail_bytes(tiff, limits.max_bytes)
    if blob == b"":
        raise ThumbnailError("IFD1 points to a thumbnail of 0 bytes")
    return None if blob is None else decode(blob, limits.max_pixels)


def _details(img: Image.Image | None, cmp: Comparison | None, limits: ThumbnailThresholds, **extra) -> dict:
    out = {
        "present": img is not None,
        "width": img.size[0] if img is not None else None,
        "height": img.size[1] if img is not None else None,
        "thresholds": {
            "max_bytes": limits.max_bytes, "max_pixels": limits.max_pixels,
            "aspect_tolerance": limits.aspect_tolerance, "min_correlation": limits.min_correlation,
            "blur_px": limits.blur_px, "change_threshold": limits.change_threshold,
            "max_region_fraction": limits.max_region_fraction,
        },
        **extra,
    }
    if cmp is not None:
        out.update({
            "box": list(cmp.box),
            "aspect_image": round(cmp.aspect_image, 4),
            "aspect_thumbnail": round(cmp.aspect_thumbnail, 4),
            "aspect_difference": round(cmp.aspect_difference, 4),
            "aspect_tolerance_applied": round(cmp.aspect_tolerance, 4),
            "rotated": cmp.rotated,
            "correlation": None if cmp.correlation is None else round(cmp.correlation, 4),
            "correlation_outside": None if cmp.correlation_outside is None else round(cmp.correlation_outside, 4),
            "gain": None if cmp.gain is None else round(cmp.gain, 4),
            "offset": None if cmp.offset is None else round(cmp.offset, 4),
            "psnr_db": None if cmp.psnr_db is None else round(cmp.psnr_db, 2),
            "changed_fraction": None if cmp.changed_fraction is None else round(cmp.changed_fraction, 4),
            "region_fraction": None if cmp.region_fraction is None else round(cmp.region_fraction, 4),
            "changed_box": None if cmp.changed_box is None else list(cmp.changed_box),
        })
    return out


def thumbnail_check(data: bytes, file_format: str, pixels: np.ndarray,
                    limits: ThumbnailThresholds) -> tuple[Check, dict]:
    """The thumbnail check and its numbers for the finding's details."""
    title = "Embedded thumbnail"
    try:
        img = extract(data, file_format, limits)
    except ThumbnailError as exc:
        return (Check("thumbnail", title, "note", f"The EXIF names a thumbnail that cannot be used: {exc}."),
                _details(None, None, limits, error=str(exc)))
    if img is None:
        return (Check("thumbnail", title, "not available", "The file carries no JPEG thumbnail in IFD1."),
                _details(None, None, limits))
    thumb = luma_of(img)
    cmp = compare(pixels, thumb, limits.aspect_tolerance, limits.blur_px, limits.change_threshold)
    details = _details(img, cmp, limits)
    size = f"{img.size[0]} x {img.size[1]}"
    if cmp.correlation is None and cmp.aspect_difference <= cmp.aspect_tolerance:
        return Check("thumbnail", title, "note",
                     f"The {size} thumbnail or the image is flat or too small to compare."), details
    if cmp.aspect_difference > cmp.aspect_tolerance:
        how = ("the image turned by 90 degrees: the pixels were rotated after the thumbnail was written"
               if cmp.rotated else "another framing: the image was cropped or the thumbnail belongs to another picture")
        return Check("thumbnail", title, "suspicious",
                     f"The {size} thumbnail's picture has aspect ratio {cmp.aspect_thumbnail:.3f}, the image "
                     f"{cmp.aspect_image:.3f} (log difference {cmp.aspect_difference:.3f} > "
                     f"{cmp.aspect_tolerance:.3f}); it shows {how}."), details
    numbers = (f"correlation {cmp.correlation:.3f} (minimum {limits.min_correlation:g}), PSNR {cmp.psnr_db:.1f} dB, "
               f"largest region differing by more than {limits.change_threshold:g} in luma "
               f"{100 * cmp.region_fraction:.2f}% of its area (maximum {100 * limits.max_region_fraction:g}%)")
    local = (cmp.region_fraction > limits.max_region_fraction and cmp.correlation_outside is not None
             and cmp.correlation_outside >= limits.min_correlation)
    if local:
        x0, y0, x1, y1 = cmp.changed_box
        return Check("thumbnail", title, "suspicious",
                     f"The {size} thumbnail differs from the stored picture in places: {numbers}; largest differing "
                     f"region at thumbnail pixels ({x0}, {y0})-({x1}, {y1}), the rest matching (correlation "
                     f"{cmp.correlation_outside:.3f})."), details
    if cmp.correlation < limits.min_correlation or cmp.region_fraction > limits.max_region_fraction:
        return Check("thumbnail", title, "suspicious",
                     f"The {size} thumbnail does not show the stored picture: {numbers}."), details
    return (Check("thumbnail", title, "consistent", f"The {size} thumbnail matches the stored picture: {numbers}."),
            details)
