"""Photos as they arrive today: WebP, HEIF and AVIF intake, containers with several images, detectors that
declare the formats they apply to, and the intake's pixel limit on every decoder. All files are made here from
the suite's own chessboard photo (tests/data/calibration)."""

import io
import json

import numpy as np
import pytest
from PIL import Image

from forensics_core import Status, analyze, load_evidence
from forensics_plugins.jpeg_grid.luminance import luminance

from test_cli import run


@pytest.fixture(scope="module")
def chessboard(data_dir):
    with Image.open(data_dir / "calibration" / "left01.jpg") as img:
        return img.convert("RGB")


@pytest.mark.parametrize("fmt, suffix", [("WEBP", "webp"), ("AVIF", "avif"), ("HEIF", "heic")])
def test_webp_avif_and_heif_are_taken_in(chessboard, tmp_path, fmt, suffix):
    path = tmp_path / f"photo.{suffix}"
    chessboard.save(path, fmt, quality=85)
    ev = load_evidence(path)
    assert ev.info.format == fmt
    assert ev.pixels.shape == (480, 640, 3)
    assert ev.info.other_images == []
    assert abs(float(ev.luma.mean()) - float(np.asarray(chessboard.convert("L")).mean()) / 255) < 0.02


def test_other_images_of_a_container_are_listed_not_analysed(chessboard, tmp_path):
    small = chessboard.resize((160, 120))
    chessboard.save(tmp_path / "two.heic", "HEIF", save_all=True, append_images=[small], quality=85)
    chessboard.convert("L").save(tmp_path / "pages.tif", save_all=True, append_images=[small, small.rotate(90, expand=True)])
    chessboard.save(tmp_path / "stereo.mpo", "MPO", save_all=True, append_images=[small])
    heif = load_evidence(tmp_path / "two.heic").info
    assert [(c.index, c.kind, c.width, c.height) for c in heif.other_images] == [(1, "HEIF image", 160, 120)]
    tiff = load_evidence(tmp_path / "pages.tif")
    assert tiff.pixels.shape == (480, 640)
    assert [(c.index, c.kind, c.width, c.height) for c in tiff.info.other_images] == [(1, "page", 160, 120),
                                                                                     (2, "page", 120, 160)]
    mpo = load_evidence(tmp_path / "stereo.mpo").info
    assert mpo.format == "MPO" and mpo.width == 640
    assert [(c.index, c.width, c.height) for c in mpo.other_images] == [(1, 160, 120)]
    assert mpo.other_images[0].kind.startswith("MPO")


def test_detectors_whose_null_was_not_checked_on_a_format_are_skipped_with_the_reason(chessboard, tmp_path, validate):
    path = tmp_path / "photo.webp"
    chessboard.save(path, "WEBP", quality=90)
    findings = analyze(path, isolation="inline")
    validate(findings)
    status = {d.name: d for d in findings.detectors}
    for name in ("jpeg_grid", "cfa"):
        assert status[name].status is Status.SKIPPED
        assert "WEBP" in status[name].summary and "JPEG" in status[name].summary
    assert status["lens_distortion"].status is not Status.SKIPPED
    assert status["metadata"].status is not Status.SKIPPED


def test_a_heif_photo_gets_a_signed_report_that_verifies(chessboard, tmp_path, validate):
    path = tmp_path / "phone.heic"
    chessboard.save(path, "HEIF", save_all=True, append_images=[chessboard.resize((320, 240))], quality=85)
    out = run("analyze", path, "--out", tmp_path / "out", "--detectors", "metadata,jpeg_grid")
    assert out.returncode == 0, out.stderr
    bundle = tmp_path / "out" / "phone"
    findings = validate(json.loads((bundle / "findings.json").read_text()))
    assert findings["evidence"]["format"] == "HEIF"
    assert findings["evidence"]["other_images"] == [{"index": 1, "kind": "HEIF image", "width": 320, "height": 240}]
    assert "HEIF image 1 (320 × 240)" in (bundle / "report.html").read_text()
    assert (bundle / "report.pdf").read_bytes().startswith(b"%PDF")
    verified = run("verify", bundle)
    assert verified.returncode == 0, verified.stdout + verified.stderr


@pytest.mark.parametrize("fmt, suffix", [("WEBP", "webp"), ("AVIF", "avif")])
def test_webp_and_avif_photos_get_a_signed_report_that_verifies(chessboard, tmp_path, validate, fmt, suffix):
    path = tmp_path / f"shared.{suffix}"
    chessboard.save(path, fmt, quality=85)
    out = run("analyze", path, "--out", tmp_path / "out", "--detectors", "metadata,dq,provenance")
    assert out.returncode == 0, out.stderr
    bundle = tmp_path / "out" / "shared"
    findings = validate(json.loads((bundle / "findings.json").read_text()))
    assert findings["evidence"]["format"] == fmt
    assert {d["name"]: d["status"] for d in findings["detectors"]}["dq"] == "skipped"
    assert (bundle / "report.pdf").read_bytes().startswith(b"%PDF")
    verified = run("verify", bundle, "--evidence", path)
    assert verified.returncode == 0, verified.stdout + verified.stderr


@pytest.fixture
def small_pillow_limit():
    """Pillow's own bomb limit far below the photo's size, as a 100 MP photo meets the default 89 MP."""
    previous = Image.MAX_IMAGE_PIXELS
    Image.MAX_IMAGE_PIXELS = 10_000
    yield
    Image.MAX_IMAGE_PIXELS = previous


def test_a_detector_decoding_again_is_held_to_the_intake_limit_not_pillows(photo, small_pillow_limit):
    ev = load_evidence(photo, max_pixels=640 * 480)
    assert luminance(ev).source == "jpeg_grey"  # the decoder's own channel, not the fallback luma
    with ev.open_image(("JPEG",)) as img:
        assert img.size == (640, 480)
    assert Image.MAX_IMAGE_PIXELS == 10_000


def test_a_tiff_of_thousands_of_pages_is_taken_in_on_its_first_with_a_bounded_list(tmp_path):
    # 100,000 pages were read header by header before any time limit, and all listed in the findings.
    from forensics_core.evidence import MAX_LISTED_IMAGES

    page = Image.new("L", (8, 8), 128)
    page.save(tmp_path / "many.tif", save_all=True, append_images=[page] * 3000)
    ev = load_evidence(tmp_path / "many.tif")
    listed = ev.info.other_images
    assert len(listed) == MAX_LISTED_IMAGES and listed[-1].kind.startswith("more pages, not listed")
    assert [c.index for c in listed[:-1]] == list(range(1, MAX_LISTED_IMAGES))


def test_a_tiff_whose_second_page_is_broken_is_analysed_on_its_first(chessboard, tmp_path):
    buf = io.BytesIO()
    chessboard.save(buf, "TIFF", save_all=True, append_images=[chessboard.resize((320, 240))])
    data = bytearray(buf.getvalue())
    second = data.rfind(b"\x01\x01\x04\x00")  # the second page's ImageLength (0x0101, LONG, little-endian)
    data[second:second + 2] = b"\x00\x00"
    path = tmp_path / "pages.tif"
    path.write_bytes(bytes(data))
    ev = load_evidence(path)
    assert ev.pixels.shape[:2] == (480, 640)
    assert ev.info.other_images and ev.info.other_images[0].kind.startswith("unreadable page")


def test_an_avif_rotation_property_is_named_and_the_stored_grid_analysed(chessboard, tmp_path):
    exif = Image.Exif()
    exif[0x0112] = 6  # Pillow writes it as the container's irot and imir properties
    path = tmp_path / "rotated.avif"
    chessboard.save(path, "AVIF", quality=85, exif=exif.tobytes())
    ev = load_evidence(path)
    assert ev.pixels.shape == (480, 640, 3) and ev.info.orientation == 6
    assert "irot" in ev.info.decoder_note and "as stored" in ev.info.decoder_note


def _with_a_second_ipma(avif: bytes) -> bytes:
    """``avif`` with its property-association box repeated, as an early encoder wrote files libavif now refuses."""
    def box(data, start, kind):
        at = data.index(kind, start) - 4
        return at, int.from_bytes(data[at:at + 4], "big")
    meta, meta_size = box(avif, 0, b"meta")
    iprp, iprp_size = box(avif, meta, b"iprp")
    ipma, ipma_size = box(avif, iprp, b"ipma")
    extra = avif[ipma:ipma + ipma_size]
    out = bytearray(avif[:ipma + ipma_size] + extra + avif[ipma + ipma_size:])
    for at, size in ((meta, meta_size), (iprp, iprp_size)):
        out[at:at + 4] = (size + len(extra)).to_bytes(4, "big")
    return bytes(out)


def test_an_avif_its_decoder_refuses_is_refused_with_the_decoders_reason(chessboard, tmp_path):
    buffer = io.BytesIO()
    chessboard.save(buffer, "AVIF", quality=85)
    path = tmp_path / "early-encoder.avif"
    path.write_bytes(_with_a_second_ipma(buffer.getvalue()))
    out = run("analyze", path, "--out", tmp_path / "out", "--format", "json")
    assert out.returncode == 1
    line = out.stderr.strip()
    assert "\n" not in line and "AVIF" in line and "libavif" in line and "not an image" not in line
