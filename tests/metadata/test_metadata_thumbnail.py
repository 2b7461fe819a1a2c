"""The IFD1 thumbnail: safe extraction from hostile bytes, picture area, comparison."""

import io
import struct

import numpy as np
import pytest
from PIL import Image

from forensics_core.evidence import load_evidence
from forensics_plugins.metadata.thumbnail import (
    ThumbnailError,
    ThumbnailThresholds,
    compare,
    content_box,
    decode,
    exif_block,
    luma_of,
    thumbnail_bytes,
    thumbnail_check,
)
from metadata_helpers import DATA, camera_thumbnail, exif_bytes, jpeg, photo, with_thumbnail

LIMITS = ThumbnailThresholds(max_bytes=262144, max_pixels=1048576, aspect_tolerance=0.03, min_correlation=0.9,
                             blur_px=1.5, change_threshold=0.12, max_region_fraction=0.005)


def _tiff(block: bytes) -> bytes:
    return block[6:]


def test_exif_block_found_after_other_segments():
    img = photo()
    data = jpeg(img, with_thumbnail(exif_bytes(make="Canon"), camera_thumbnail(img)), icc_profile=b"\x00" * 200)
    tiff = exif_block(data, "JPEG")
    assert tiff[:2] in (b"II", b"MM")
    assert thumbnail_bytes(tiff, LIMITS.max_bytes)[:2] == b"\xff\xd8"


def test_exif_block_absent_or_malformed():
    assert exif_block(jpeg(photo()), "JPEG") is None
    with pytest.raises(ThumbnailError, match="SOI"):
        exif_block(b"not a jpeg", "JPEG")
    # An APP1 segment claiming more bytes than the file has.
    with pytest.raises(ThumbnailError, match="past the end"):
        exif_block(b"\xff\xd8\xff\xe1\xff\xf0Exif\x00\x00MM", "JPEG")
    with pytest.raises(ThumbnailError, match="no JPEG marker"):
        exif_block(b"\xff\xd8\x00\x00\x00\x00", "JPEG")


def test_png_exif_chunk():
    img = photo((64, 48))
    buf = io.BytesIO()
    img.save(buf, "PNG", exif=exif_bytes(make="Canon"))
    assert exif_block(buf.getvalue(), "PNG")[:2] in (b"II", b"MM")
    assert exif_block(jpeg(img), "PNG") is None


@pytest.mark.parametrize("lie, message", [
    ({"offset": 10_000_000}, "outside"),
    ({"length": 10_000_000}, "more than"),
    ({"offset": 8, "length": 40}, "not a JPEG"),
    ({"ifd1_offset": 10_000_000}, "outside"),
    ({"ifd1_offset": 3}, "outside"),
])
def test_bogus_thumbnail_pointers_are_refused(lie, message):
    block = with_thumbnail(exif_bytes(make="Canon"), camera_thumbnail(photo()), **lie)
    with pytest.raises(ThumbnailError, match=message):
        thumbnail_bytes(_tiff(block), LIMITS.max_bytes)


def test_zero_length_and_missing_ifd1():
    block = with_thumbnail(exif_bytes(make="Canon"), b"", length=0)
    assert thumbnail_bytes(_tiff(block), LIMITS.max_bytes) == b""
    assert thumbnail_bytes(_tiff(exif_bytes(make="Canon")), LIMITS.max_bytes) is None


def test_huge_entry_count_and_bad_header():
    tiff = bytearray(_tiff(exif_bytes(make="Canon")))
    (ifd0,) = struct.unpack_from(">I", tiff, 4)
    struct.pack_into(">H", tiff, ifd0, 60000)
    with pytest.raises(ThumbnailError, match="entries"):
        thumbnail_bytes(bytes(tiff), LIMITS.max_bytes)
    with pytest.raises(ThumbnailError, match="TIFF header"):
        thumbnail_bytes(b"XX\x00*\x00\x00\x00\x08", LIMITS.max_bytes)


def test_decode_limits():
    thumb = camera_thumbnail(photo())
    assert decode(thumb, 160 * 120).size == (160, 120)
    with pytest.raises(ThumbnailError, match="accepted"):
        decode(thumb, 1000)
    with pytest.raises(ThumbnailError, match="does not decode"):
        decode(thumb[:200], LIMITS.max_pixels)


def test_letterbox_bands_are_found():
    thumb = np.full((120, 160), 0.0)
    thumb[6:113] = np.random.default_rng(0).random((107, 160))  # a 3:2 picture in a 4:3 frame
    assert content_box(thumb, 1.5, 0.04) == (0, 6, 160, 113)
    # Bands that are not uniform are picture, not letterbox.
    noisy = np.random.default_rng(1).random((120, 160))
    assert content_box(noisy, 1.5, 0.04) == (0, 0, 160, 120)


def test_matching_thumbnail():
    img = photo()
    cmp = compare(np.asarray(img), luma_of(Image.open(io.BytesIO(camera_thumbnail(img)))), 0.03, 1.5, 0.12)
    assert cmp.correlation > 0.99 and cmp.region_fraction < 0.001 and cmp.aspect_difference < 0.01


def test_local_edit_is_located():
    img = photo()
    thumb = luma_of(Image.open(io.BytesIO(camera_thumbnail(img))))
    edited = np.asarray(img).copy()
    edited[300:420, 60:220] = 255 - edited[300:420, 60:220]
    cmp = compare(edited, thumb, 0.03, 1.5, 0.12)
    assert cmp.region_fraction > 0.02
    # The edit spans thumbnail pixels x 15-55, y 75-105; the blur spreads it by about 3.
    x0, y0, x1, y1 = cmp.changed_box
    assert 12 <= x0 and 72 <= y0 and x1 <= 58 and y1 <= 108


def test_crop_and_rotation_change_the_aspect():
    img = photo()
    thumb = luma_of(Image.open(io.BytesIO(camera_thumbnail(img))))
    cropped = compare(np.asarray(img)[:, :500], thumb, 0.03, 1.5, 0.12)
    assert cropped.aspect_difference > cropped.aspect_tolerance and not cropped.rotated and cropped.correlation is None
    rotated = compare(np.rot90(np.asarray(img)), thumb, 0.03, 1.5, 0.12)
    assert rotated.rotated


def test_check_outcomes_on_real_files():
    canon = load_evidence(DATA / "exif" / "canon_hdr_NO.jpg")
    check, details = thumbnail_check(canon.data, canon.info.format, canon.pixels, LIMITS)
    assert check.outcome == "consistent" and details["correlation"] > 0.99
    casio = load_evidence(DATA / "exif" / "35-empty.jpg")
    check, details = thumbnail_check(casio.data, casio.info.format, casio.pixels, LIMITS)
    assert check.outcome == "suspicious" and details["correlation"] < 0.5
    nikon = load_evidence(DATA / "exif" / "87_OSError.jpg")
    check, details = thumbnail_check(nikon.data, nikon.info.format, nikon.pixels, LIMITS)
    assert check.outcome == "note" and "0 bytes" in check.observation and not details["present"]
