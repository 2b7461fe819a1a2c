"""The embedded EXIF thumbnail (IFD1), read once at intake from hostile bytes.

A camera writes a small JPEG of the picture into the EXIF block (IFD1, tags
JPEGInterchangeFormat 0x0201 and JPEGInterchangeFormatLength 0x0202, offsets
counted from the TIFF header; Exif 2.32). Every number that leads to it comes
from the evidence, so the reading is strict: find the EXIF block in the file
(:func:`exif_block`), walk the TIFF structure to IFD1 with every offset
bounds-checked (:func:`thumbnail_pointer`), and
decode the thumbnail as a JPEG only, under a size and pixel limit, with
Pillow's decompression-bomb warning as an error (:func:`decode`).
:func:`read_thumbnail` does all of it for :func:`.evidence.load_evidence`
and never raises: a thumbnail that cannot be read safely is kept as the
one-sentence reason (:class:`EmbeddedThumbnail`).
"""

from __future__ import annotations

import io
import struct
import warnings
from dataclasses import dataclass

import numpy as np
from PIL import Image

#: Largest thumbnail read, in bytes: the standard limits a thumbnail to 64 kB,
#: and anything much larger is not one.
MAX_BYTES = 256 * 1024
#: Largest thumbnail decoded, in pixels.
MAX_PIXELS = 1024 * 1024

# Pillow's names of the formats whose EXIF sits in an APP1 marker segment.
_JPEG_FORMATS = ("JPEG", "MPO")
_EXIF_HEADER = b"Exif\x00\x00"
_MAX_IFD_ENTRIES = 1024
_TAG_JPEG_OFFSET, _TAG_JPEG_LENGTH = 0x0201, 0x0202
# What Pillow raises on malformed bytes besides OSError (as the intake's own
# decoding meets them), and its decompression-bomb refusals.
_OPEN_ERRORS = (OSError, ValueError, SyntaxError, EOFError, TypeError, KeyError, IndexError, struct.error,
                Image.DecompressionBombError, Image.DecompressionBombWarning)


class ThumbnailError(ValueError):
    """The file's thumbnail data is malformed; the message says how, in one sentence.

    Attributes
    ----------
    size : tuple of int or None
        ``(width, height)`` the thumbnail's JPEG header claims, when the
        error came after it was read.
    """

    def __init__(self, message: str, size: tuple[int, int] | None = None) -> None:
        super().__init__(message)
        self.size = size


@dataclass(frozen=True, eq=False)
class EmbeddedThumbnail:
    """The JPEG thumbnail a file's EXIF names in IFD1, as read at intake.

    Either ``pixels`` holds the decoded thumbnail or ``error`` says why it
    could not be read safely; the other fields keep what was read before
    that, so that a caller with tighter limits than the intake's can refuse
    it as the parser would have (:meth:`refusal`).

    Attributes
    ----------
    offset, length : int or None
        Where IFD1 places the thumbnail (bytes from the TIFF header) and how
        many bytes it claims; None when the EXIF could not be read as far as
        IFD1's tags.
    size : tuple of int or None
        ``(width, height)`` the thumbnail's JPEG header claims, when it was read.
    jpeg : bytes or None
        The thumbnail's bytes as stored in the file, when they lie inside the
        EXIF block and start a JPEG stream.
    pixels : numpy.ndarray or None, shape (h, w, 3)
        The decoded thumbnail, RGB ``uint8``, read-only; orientation not applied.
    error : str or None
        Why the thumbnail cannot be used, in one sentence; None when ``pixels`` is set.
    """

    offset: int | None = None
    length: int | None = None
    size: tuple[int, int] | None = None
    jpeg: bytes | None = None
    pixels: np.ndarray | None = None
    error: str | None = None

    @property
    def named(self) -> bool:
        """IFD1 gives the thumbnail a non-zero offset and length (``ExifSummary.thumbnail_present``)."""
        return bool(self.offset) and bool(self.length)

    def image(self) -> Image.Image | None:
        """The decoded thumbnail as a new RGB Pillow image, or None when it could not be read."""
        return None if self.pixels is None else Image.fromarray(self.pixels)

    def refusal(self, max_bytes: int = MAX_BYTES, max_pixels: int = MAX_PIXELS) -> str | None:
        """Why the thumbnail cannot be used under these limits, in one sentence, or None when it can.

        Limits above the intake's (:data:`MAX_BYTES`, :data:`MAX_PIXELS`)
        cannot admit what the intake refused; tighter ones refuse with the
        parser's own sentence, in the parser's order (the claimed length is
        checked before the bytes are located, the claimed pixel count before
        they are decoded).

        Parameters
        ----------
        max_bytes : int
            Largest thumbnail accepted, bytes.
        max_pixels : int
            Largest thumbnail accepted, pixels.
        """
        if self.length and self.length > max_bytes:
            return _too_many_bytes(self.length, max_bytes)
        if self.size is not None and not _pixels_accepted(self.size, max_pixels):
            return _too_many_pixels(self.size, max_pixels)
        return self.error


def _too_many_bytes(length: int, max_bytes: int) -> str:
    return f"IFD1 claims a {length}-byte thumbnail, more than the {max_bytes} bytes accepted"


def _pixels_accepted(size: tuple[int, int], max_pixels: int) -> bool:
    w, h = size
    return w >= 1 and h >= 1 and w * h <= max_pixels


def _too_many_pixels(size: tuple[int, int], max_pixels: int) -> str:
    return f"the thumbnail claims {size[0]} x {size[1]} pixels, outside the accepted 1 to {max_pixels}"


def exif_block(data: bytes, file_format: str) -> bytes | None:
    """The TIFF structure of the file's EXIF, without the ``Exif\\0\\0`` header.

    For a JPEG the marker segments before the first scan are walked and the
    first APP1 segment holding EXIF is returned; for other formats Pillow's
    reading of the EXIF chunk is used.

    Parameters
    ----------
    data : bytes
        The file's bytes.
    file_format : str
        Pillow's name of its format (``EvidenceInfo.format``).

    Returns
    -------
    bytes or None
        None when the file carries no EXIF (or Pillow cannot open it).

    Raises
    ------
    ThumbnailError
        When a JPEG marker segment runs past the end of the file.
    """
    if file_format not in _JPEG_FORMATS:
        try:
            with Image.open(io.BytesIO(data)) as img:
                raw = img.info.get("exif")
        except _OPEN_ERRORS:
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


def thumbnail_pointer(tiff: bytes) -> tuple[int, int] | None:
    """Where IFD1 places its JPEG thumbnail, ``(offset, length)``, or None when it names none.

    Parameters
    ----------
    tiff : bytes
        The EXIF TIFF structure (from :func:`exif_block`).

    Returns
    -------
    tuple of int or None
        Offset from the TIFF header and length in bytes, as IFD1 claims them
        (not yet checked against the block); None when there is no IFD1 or
        it has neither tag.

    Raises
    ------
    ThumbnailError
        On a malformed header or IFD, an IFD outside the block, or an IFD1
        with one of the two tags but not the other.
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
    return offset, length


def _stored(tiff: bytes, offset: int, length: int, max_bytes: int) -> bytes:
    """The ``length`` bytes at ``offset`` of the block, checked to lie inside it and to start a JPEG stream."""
    if length == 0:
        return b""
    if length > max_bytes:
        raise ThumbnailError(_too_many_bytes(length, max_bytes))
    if offset < 8 or offset + length > len(tiff):
        raise ThumbnailError(f"IFD1 places the thumbnail at bytes {offset}-{offset + length}, outside the "
                             f"{len(tiff)}-byte EXIF block")
    blob = tiff[offset:offset + length]
    if blob[:2] != b"\xff\xd8":
        raise ThumbnailError("the bytes IFD1 points to are not a JPEG stream")
    return blob


def decode(blob: bytes, max_pixels: int) -> Image.Image:
    """The thumbnail decoded as RGB, refusing more than ``max_pixels`` pixels.

    Only Pillow's JPEG decoder is tried, and its decompression-bomb warning
    is an error.

    Raises
    ------
    ThumbnailError
        When it does not decode or is too large; its ``size`` is what the
        JPEG header claims, once read.
    """
    size = None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(io.BytesIO(blob), formats=["JPEG"]) as img:
                size = img.size
                if not _pixels_accepted(size, max_pixels):
                    raise ThumbnailError(_too_many_pixels(size, max_pixels), size)
                img.load()
                return img.convert("RGB")
    except ThumbnailError:
        raise
    except _OPEN_ERRORS as exc:
        raise ThumbnailError(f"the thumbnail does not decode ({type(exc).__name__})", size) from None


def read_thumbnail(data: bytes, file_format: str, max_bytes: int = MAX_BYTES,
                   max_pixels: int = MAX_PIXELS) -> EmbeddedThumbnail | None:
    """The file's EXIF thumbnail, read and decoded, or why it cannot be: never raises.

    Parameters
    ----------
    data : bytes
        The file's bytes.
    file_format : str
        Pillow's name of its format.
    max_bytes, max_pixels : int
        Larger thumbnails are refused (kept as the reason).

    Returns
    -------
    EmbeddedThumbnail or None
        None when the file has no EXIF, no IFD1, or an IFD1 naming no JPEG
        thumbnail; otherwise the decoded thumbnail, or ``error`` set when the
        EXIF up to the thumbnail is malformed or the thumbnail is empty,
        outside the block, too large, not a JPEG or does not decode.

    Examples
    --------
    >>> from pathlib import Path
    >>> thumb = read_thumbnail(Path("tests/data/exif/Canon_40D.jpg").read_bytes(), "JPEG")
    >>> thumb.size, thumb.pixels.shape, thumb.error
    ((68, 46), (46, 68, 3), None)
    """
    try:
        tiff = exif_block(data, file_format)
        pointer = None if tiff is None else thumbnail_pointer(tiff)
    except ThumbnailError as exc:
        return EmbeddedThumbnail(error=str(exc))
    if pointer is None:
        return None
    offset, length = pointer
    try:
        blob = _stored(tiff, offset, length, max_bytes)
    except ThumbnailError as exc:
        return EmbeddedThumbnail(offset, length, error=str(exc))
    if not blob:
        return EmbeddedThumbnail(offset, length, error="IFD1 points to a thumbnail of 0 bytes")
    try:
        img = decode(blob, max_pixels)
    except ThumbnailError as exc:
        return EmbeddedThumbnail(offset, length, exc.size, blob, error=str(exc))
    pixels = np.asarray(img)
    pixels.flags.writeable = False
    return EmbeddedThumbnail(offset, length, img.size, blob, pixels)
