"""Evidence intake on real camera files and on hostile input."""

import errno
import hashlib
import os
import struct
import zlib

import numpy as np
import pytest
from PIL import Image

from forensics_core import EvidenceError, load_evidence

EXIF = "exif"


def png_header_only(width: int, height: int) -> bytes:
    """A PNG that claims ``width`` x ``height`` pixels but carries almost no data."""

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + chunk(b"IEND", b"")


def test_hashes_are_of_the_original_bytes(data_dir):
    path = data_dir / EXIF / "Canon_40D.jpg"
    raw = path.read_bytes()
    ev = load_evidence(path)
    assert ev.info.sha256 == hashlib.sha256(raw).hexdigest()
    assert ev.info.sha512 == hashlib.sha512(raw).hexdigest()
    assert ev.info.md5 == hashlib.md5(raw).hexdigest()
    assert ev.info.size == len(raw) and ev.data == raw
    assert ev.info.hashed_at.endswith("Z")


def test_exif_of_a_real_camera_file_with_gps_and_editor(data_dir):
    info = load_evidence(data_dir / EXIF / "Canon_40D.jpg").info
    exif = info.exif
    assert (exif.make, exif.model) == ("Canon", "Canon EOS 40D")
    assert exif.focal_length_mm == 135.0
    assert exif.software == "GIMP 2.4.5"
    assert exif.datetime_original == "2008:05:30 15:56:01"
    assert exif.thumbnail_present
    assert info.icc_profile
    assert (info.width, info.height, info.format) == (100, 68, "JPEG")
    assert set(info.quantization_tables) == {"0", "1"} and len(info.quantization_tables["0"]) == 64
    names = {(t.ifd, t.name) for t in exif.raw}
    assert ("Exif", "ExposureTime") in names and ("IFD0", "Make") in names


def test_exif_lens_and_gps_position(data_dir):
    exif = load_evidence(data_dir / EXIF / "87_OSError.jpg").info.exif
    assert exif.make == "NIKON CORPORATION" and exif.model == "NIKON D70s"
    assert exif.lens_model is None or "18.0-70.0" in exif.lens_model
    assert exif.gps is not None
    assert exif.gps.latitude == pytest.approx(43 + 47.135666 / 60, abs=1e-6)
    assert exif.gps.longitude == pytest.approx(11 + 14.077166 / 60, abs=1e-6)
    assert exif.gps.altitude_m == pytest.approx(42.123)


def test_orientation_is_reported_not_applied(data_dir):
    ev = load_evidence(data_dir / EXIF / "canon_hdr_NO.jpg")
    assert ev.info.orientation == 6
    assert (ev.info.width, ev.info.height) == (2048, 1536)
    assert ev.pixels.shape == (1536, 2048, 3)


def test_photoshop_software_tag(data_dir):
    assert "Photoshop" in load_evidence(data_dir / EXIF / "BlueSquare.jpg").info.exif.software


def test_pixels_and_luma_are_read_only(data_dir):
    ev = load_evidence(data_dir / "calibration" / "left01.jpg")
    assert ev.pixels.shape == (480, 640) and ev.pixels.dtype == np.uint8
    assert not ev.pixels.flags.writeable and not ev.luma.flags.writeable
    assert 0.0 <= ev.luma.min() and ev.luma.max() <= 1.0


def test_hostile_exif_strings_are_kept_as_text(tmp_path, data_dir):
    img = Image.open(data_dir / "calibration" / "left01.jpg")
    exif = Image.Exif()
    exif[0x010F] = "<script>alert(1)</script>"
    exif[0x0110] = '<img src="file:///etc/passwd">\x1b[31m'
    path = tmp_path / "hostile.jpg"
    img.save(path, exif=exif)
    info = load_evidence(path).info
    assert info.exif.make == "<script>alert(1)</script>"
    assert info.exif.model == '<img src="file:///etc/passwd">\\x1b[31m'


def test_sixteen_bit_png_and_tiff(tmp_path):
    arr = (np.arange(64 * 48, dtype=np.uint32).reshape(48, 64) * 20).astype(np.uint16)
    Image.fromarray(arr).save(tmp_path / "a.png")
    Image.fromarray(arr).save(tmp_path / "a.tif")
    for name in ("a.png", "a.tif"):
        ev = load_evidence(tmp_path / name)
        assert ev.pixels.dtype == np.uint16 and ev.pixels.shape == (48, 64)
        assert ev.luma.max() == pytest.approx(arr.max() / 65535.0)


def bad_inputs(tmp_path, data_dir):
    real = (data_dir / "calibration" / "left01.jpg").read_bytes()
    (tmp_path / "empty.jpg").write_bytes(b"")
    (tmp_path / "text.jpg").write_bytes(b"this is not an image at all\n" * 20)
    (tmp_path / "truncated.jpg").write_bytes(real[: len(real) // 2])
    Image.new("RGB", (8, 8)).save(tmp_path / "anim.gif")
    (tmp_path / "bomb.png").write_bytes(png_header_only(20000, 20000))
    (tmp_path / "adir").mkdir()
    (tmp_path / "loop.jpg").symlink_to("loop2.jpg")
    (tmp_path / "loop2.jpg").symlink_to("loop.jpg")
    return {
        "missing.jpg": "no such file",
        "loop.jpg": f"cannot read: {os.strerror(errno.ELOOP)}",
        "adir": "is a directory",
        "empty.jpg": "empty file",
        "text.jpg": "not an image",
        "truncated.jpg": "truncated",
        "anim.gif": "unsupported format GIF",
        "bomb.png": "exceeds the pixel limit",
    }


def test_every_bad_input_gets_a_one_line_reason(tmp_path, data_dir):
    for name, reason in bad_inputs(tmp_path, data_dir).items():
        with pytest.raises(EvidenceError) as err:
            load_evidence(tmp_path / name)
        assert reason in str(err.value), name
        assert "\n" not in str(err.value)


def test_pixel_limit_is_configurable(data_dir):
    with pytest.raises(EvidenceError, match="pixel limit"):
        load_evidence(data_dir / "calibration" / "left01.jpg", max_pixels=640 * 480 - 1)
    assert load_evidence(data_dir / "calibration" / "left01.jpg", max_pixels=640 * 480).info.width == 640
