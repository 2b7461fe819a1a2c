"""The EXIF (IFD1) thumbnail read once at intake: safe parsing of hostile bytes, and an intake that never fails on it."""

import io
import re
import struct
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import forensics_core
from forensics_core import load_evidence
from forensics_core import thumbnail as core_thumbnail
from forensics_core.thumbnail import (
    MAX_BYTES,
    MAX_PIXELS,
    EmbeddedThumbnail,
    ThumbnailError,
    decode,
    exif_block,
    read_thumbnail,
)

DATA = Path(__file__).resolve().parents[1] / "data"


def _photo(size=(640, 480)) -> Image.Image:
    with Image.open(DATA / "exif" / "canon_hdr_NO.jpg") as img:
        return img.convert("RGB").resize(size, Image.Resampling.LANCZOS)


def _jpeg(img: Image.Image, exif: bytes | None = None, **save) -> bytes:
    buf = io.BytesIO()
    img.save(buf, "JPEG", quality=90, **({"exif": exif} if exif is not None else {}), **save)
    return buf.getvalue()


def _thumb(img: Image.Image, size=(160, 120)) -> bytes:
    buf = io.BytesIO()
    img.resize(size, Image.Resampling.BILINEAR).save(buf, "JPEG", quality=80)
    return buf.getvalue()


def _exif(thumb: bytes, *, offset: int | None = None, length: int | None = None,
          ifd1_offset: int | None = None) -> bytes:
    """``Exif\\0\\0`` + a big-endian TIFF: IFD0 (Orientation) and IFD1 pointing at ``thumb``; the pointers may lie."""
    ifd1 = 8 + 2 + 12 + 4
    data_at = ifd1 + 2 + 2 * 12 + 4
    tiff = b"MM\x00\x2a" + struct.pack(">I", 8)
    tiff += struct.pack(">HHHIHH", 1, 0x0112, 3, 1, 1, 0) + struct.pack(">I", ifd1 if ifd1_offset is None else ifd1_offset)
    tiff += struct.pack(">H", 2)
    tiff += struct.pack(">HHII", 0x0201, 4, 1, data_at if offset is None else offset)
    tiff += struct.pack(">HHII", 0x0202, 4, 1, len(thumb) if length is None else length)
    tiff += struct.pack(">I", 0) + thumb
    return b"Exif\x00\x00" + tiff


def _tiff(block: bytes) -> bytes:
    return block[6:]


def _counting_decode(monkeypatch) -> list[int]:
    calls: list[int] = []
    original = core_thumbnail.decode

    def counted(blob, max_pixels):
        calls.append(len(blob))
        return original(blob, max_pixels)

    monkeypatch.setattr(core_thumbnail, "decode", counted)
    return calls


def test_exif_block_found_after_other_segments():
    img = _photo()
    data = _jpeg(img, _exif(_thumb(img)), icc_profile=b"\x00" * 200)
    tiff = exif_block(data, "JPEG")
    assert tiff[:2] in (b"II", b"MM")
    assert read_thumbnail(data, "JPEG").jpeg[:2] == b"\xff\xd8"


def test_exif_block_absent_or_malformed():
    assert exif_block(_jpeg(_photo()), "JPEG") is None
    with pytest.raises(ThumbnailError, match="SOI"):
        exif_block(b"not a jpeg", "JPEG")
    # An APP1 segment claiming more bytes than the file has.
    with pytest.raises(ThumbnailError, match="past the end"):
        exif_block(b"\xff\xd8\xff\xe1\xff\xf0Exif\x00\x00MM", "JPEG")
    with pytest.raises(ThumbnailError, match="no JPEG marker"):
        exif_block(b"\xff\xd8\x00\x00\x00\x00", "JPEG")


def test_png_exif_chunk():
    img = _photo((64, 48))
    exif = Image.Exif()
    exif[0x010F] = "Canon"
    buf = io.BytesIO()
    img.save(buf, "PNG", exif=exif.tobytes())
    assert exif_block(buf.getvalue(), "PNG")[:2] in (b"II", b"MM")
    assert exif_block(_jpeg(img), "PNG") is None
    assert exif_block(b"not an image", "PNG") is None


@pytest.mark.parametrize("lie, message", [
    ({"offset": 10_000_000}, "outside"),
    ({"length": 10_000_000}, "more than"),
    ({"offset": 8, "length": 40}, "not a JPEG"),
    ({"ifd1_offset": 10_000_000}, "outside"),
    ({"ifd1_offset": 3}, "outside"),
])
def test_bogus_thumbnail_pointers_are_refused(lie, message):
    found = read_thumbnail(_jpeg(_photo(), _exif(_thumb(_photo()), **lie)), "JPEG")
    assert found.pixels is None and re.search(message, found.error)


def test_zero_length_and_missing_ifd1():
    empty = read_thumbnail(_jpeg(_photo(), _exif(b"", length=0)), "JPEG")
    assert empty.error == "IFD1 points to a thumbnail of 0 bytes" and not empty.named
    exif = Image.Exif()
    exif[0x010F] = "Canon"
    assert read_thumbnail(_jpeg(_photo(), exif.tobytes()), "JPEG") is None


def test_huge_entry_count_and_bad_header():
    tiff = bytearray(_tiff(_exif(_thumb(_photo()))))
    struct.pack_into(">H", tiff, 8, 60000)
    assert "entries" in read_thumbnail(_jpeg(_photo(), b"Exif\x00\x00" + bytes(tiff)), "JPEG").error
    assert "TIFF header" in read_thumbnail(_jpeg(_photo(), b"Exif\x00\x00XX\x00*\x00\x00\x00\x08"), "JPEG").error


def test_decode_limits():
    thumb = _thumb(_photo())
    assert decode(thumb, 160 * 120).size == (160, 120)
    with pytest.raises(ThumbnailError, match="accepted") as refused:
        decode(thumb, 1000)
    assert refused.value.size == (160, 120)
    with pytest.raises(ThumbnailError, match="does not decode"):
        decode(thumb[:200], MAX_PIXELS)
    png = io.BytesIO()
    _photo((16, 12)).save(png, "PNG")
    with pytest.raises(ThumbnailError, match="does not decode"):
        decode(png.getvalue(), MAX_PIXELS)


@pytest.mark.parametrize("lie, message, named", [
    ({"offset": 10_000_000}, "outside the", True),
    ({"length": 10_000_000}, "more than the 262144 bytes accepted", True),
    ({"offset": 8, "length": 40}, "not a JPEG stream", True),
    ({"length": 0}, "IFD1 points to a thumbnail of 0 bytes", False),
    ({"ifd1_offset": 10_000_000}, "points outside", False),
])
def test_read_thumbnail_keeps_the_reason_instead_of_raising(lie, message, named):
    thumb = read_thumbnail(_jpeg(_photo(), _exif(_thumb(_photo()), **lie)), "JPEG")
    assert isinstance(thumb, EmbeddedThumbnail)
    assert message in thumb.error and thumb.pixels is None and thumb.image() is None
    assert thumb.named is named
    assert thumb.refusal() == thumb.error


def test_read_thumbnail_of_files_without_one_or_with_a_broken_stream():
    assert read_thumbnail(_jpeg(_photo()), "JPEG") is None
    exif = Image.Exif()
    exif[0x010F] = "Canon"
    assert read_thumbnail(_jpeg(_photo(), exif.tobytes()), "JPEG") is None
    assert read_thumbnail(b"\x89PNG\r\n\x1a\n", "PNG") is None
    full = _thumb(_photo())
    broken = full[:len(full) // 2]
    thumb = read_thumbnail(_jpeg(_photo(), _exif(broken)), "JPEG")
    assert "does not decode" in thumb.error and thumb.size == (160, 120) and thumb.jpeg == broken


def test_refusal_under_tighter_limits_uses_the_parsers_sentence_and_order():
    blob = _thumb(_photo())
    thumb = read_thumbnail(_jpeg(_photo(), _exif(blob)), "JPEG")
    assert thumb.error is None and thumb.refusal() is None and thumb.jpeg == blob
    assert thumb.refusal(len(blob) - 1, 10) == (f"IFD1 claims a {len(blob)}-byte thumbnail, more than the "
                                               f"{len(blob) - 1} bytes accepted")
    assert thumb.refusal(MAX_BYTES, 1000) == "the thumbnail claims 160 x 120 pixels, outside the accepted 1 to 1000"
    # Beyond the parser's checks on the length, what the intake refused stays refused.
    outside = read_thumbnail(_jpeg(_photo(), _exif(blob, offset=10_000_000)), "JPEG")
    assert outside.refusal(10 * MAX_BYTES, 10 * MAX_PIXELS) == outside.error


def test_intake_decodes_the_thumbnail_once(monkeypatch):
    calls = _counting_decode(monkeypatch)
    ev = load_evidence(DATA / "exif" / "Canon_40D.jpg")
    assert len(calls) == 1
    thumb = ev.thumbnail
    assert thumb.error is None and thumb.size == (68, 46) and thumb.named and ev.info.exif.thumbnail_present
    assert thumb.pixels.shape == (46, 68, 3) and thumb.pixels.dtype == np.uint8 and not thumb.pixels.flags.writeable
    assert thumb.image().mode == "RGB" and np.array_equal(np.asarray(thumb.image()), thumb.pixels)
    assert len(thumb.jpeg) == thumb.length and thumb.jpeg[:2] == b"\xff\xd8"


def test_intake_of_a_file_without_thumbnail(data_dir):
    ev = load_evidence(data_dir / "calibration" / "left01.jpg")
    assert ev.thumbnail is None and not ev.info.exif.thumbnail_present


@pytest.mark.parametrize("lie, message, present", [
    ({"offset": 10_000_000}, "IFD1 places the thumbnail at bytes 10000000-", True),
    ({"length": 0}, "IFD1 points to a thumbnail of 0 bytes", False),
])
def test_malformed_ifd1_is_recorded_not_fatal(tmp_path, lie, message, present):
    """An IFD1 pointing past the end or at 0 bytes: the intake succeeds and keeps the reason.

    ``thumbnail_present`` keeps its meaning (IFD1 gives a non-zero offset and length).
    """
    path = tmp_path / "lie.jpg"
    path.write_bytes(_jpeg(_photo(), _exif(_thumb(_photo()), **lie)))
    ev = load_evidence(path)
    assert ev.pixels.shape == (480, 640, 3)
    assert ev.thumbnail.pixels is None and ev.thumbnail.error.startswith(message)
    assert ev.info.exif.thumbnail_present is present


def test_the_thumbnail_is_public_api():
    assert forensics_core.EmbeddedThumbnail is EmbeddedThumbnail
    assert "EmbeddedThumbnail" in forensics_core.__all__
