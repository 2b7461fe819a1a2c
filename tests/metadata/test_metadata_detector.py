"""The metadata detector end to end: each check's positive and negative case, hostile files, the hooks, the report."""

import io
import json

import numpy as np
import pytest
from PIL import Image

from forensics_core import Status
from forensics_core.analysis import Options, analyze_evidence
from forensics_core.findings import check_result
from forensics_core.plugins import PluginHost
from forensics_core.report.plugin_sections import section_for
from forensics_plugins.metadata import plugin
from forensics_plugins.metadata.detector import Metadata
from forensics_plugins.metadata.spec import DEFAULT_PARAMS, NAME, SPEC
from metadata_helpers import (
    camera_thumbnail,
    evidence_from,
    exif_bytes,
    fake_evidence,
    info,
    jpeg,
    photo,
    with_thumbnail,
)

CAMERA = dict(make="Canon", model="Canon PowerShot SX60 HS", software=None, datetime="2021:06:01 12:00:00",
              datetime_original="2021:06:01 12:00:00", orientation=1, exif_width=640, exif_height=480, focal=8.119)


def _run(evidence, prior=None, **params):
    result = Metadata().analyze(evidence, {**DEFAULT_PARAMS, **params}, prior or {})
    check_result(result)  # JSON-serialisable, score in range, no NaN
    return result, {c["id"]: c for c in result.details["checks"]}


def _camera_file(tmp_path, img=None, thumb_img=None, **overrides):
    img = img or photo()
    tags = {**CAMERA, **overrides}
    block = with_thumbnail(exif_bytes(**tags), camera_thumbnail(thumb_img or img))
    return evidence_from(jpeg(img, block), tmp_path)


def test_spec_and_registration():
    registered = []
    plugin.forensics_register_detectors(registered.append)
    assert len(registered) == 1 and registered[0].spec == SPEC
    assert isinstance(registered[0].made(), Metadata)
    assert SPEC.uses == ("lens_distortion",) and SPEC.version == "1.2.0"
    assert json.dumps(SPEC.default_params)
    assert any("CC BY-SA 3.0" in ref for ref in SPEC.references)


def test_plain_camera_file(tmp_path):
    result, checks = _run(_camera_file(tmp_path))
    assert result.status is Status.OK and result.p_value is None and result.nfa is None
    for key in ("exif_present", "datetime", "dimensions", "thumbnail"):
        assert checks[key]["outcome"] == "consistent", checks[key]
    assert checks["software"]["outcome"] == "not available"
    # Pillow writes standard IJG tables, which Canon cameras do not.
    assert checks["quantisation"]["outcome"] == "suspicious"
    assert checks["lens"]["outcome"] == "not available" and "did not run" in checks["lens"]["observation"]
    assert result.score == pytest.approx(1 / 5)
    assert "JPEG quantisation tables" in result.summary and "never proof" in result.summary


@pytest.mark.parametrize("overrides, check, outcome", [
    ({"software": "Adobe Photoshop 24.0 (Windows)"}, "software", "suspicious"),
    ({"software": "Ver.1.00"}, "software", "consistent"),
    ({"datetime": "2021:06:03 09:00:00"}, "datetime", "suspicious"),
    ({"exif_width": 1280, "exif_height": 960}, "dimensions", "suspicious"),
    ({"exif_width": 480, "exif_height": 640, "orientation": 6}, "dimensions", "consistent"),
    ({"make": "Jolla", "model": "Jolla"}, "quantisation", "note"),
])
def test_each_check_positive_and_negative(tmp_path, overrides, check, outcome):
    _, checks = _run(_camera_file(tmp_path, **overrides))
    assert checks[check]["outcome"] == outcome, checks[check]


def test_thumbnail_of_another_picture(tmp_path):
    other = photo(source="87_OSError.jpg", size=(480, 640)).rotate(90, expand=True)
    _, checks = _run(_camera_file(tmp_path, thumb_img=other))
    assert checks["thumbnail"]["outcome"] == "suspicious" and "correlation" in checks["thumbnail"]["observation"]


def test_thumbnail_not_following_a_local_edit(tmp_path):
    img = photo()
    edited = np.asarray(img).copy()
    edited[120:240, 360:520] = np.asarray(photo(source="87_OSError.jpg", size=(160, 120)))
    evidence = _camera_file(tmp_path, img=Image.fromarray(edited), thumb_img=img)
    result, checks = _run(evidence)
    assert checks["thumbnail"]["outcome"] == "suspicious" and "in places" in checks["thumbnail"]["observation"]
    x0, y0, x1, y1 = result.details["thumbnail"]["changed_box"]
    assert 85 <= x0 and 25 <= y0 and x1 <= 135 and y1 <= 65


def test_letterboxed_thumbnail_of_a_3_2_photo_and_a_paste_resaved_with_its_exif(tmp_path):
    """A 3:2 camera-like JPEG with a 160 x 120 letterboxed thumbnail matches; a paste re-saved with its EXIF does not."""
    img = photo((960, 640))
    original = _camera_file(tmp_path, img=img, exif_width=960, exif_height=640)
    _, checks = _run(original)
    assert checks["thumbnail"]["outcome"] == "consistent", checks["thumbnail"]
    # An editor that keeps the EXIF: open the camera file, paste a region of
    # another photo, save with the EXIF block read from the original.
    with Image.open(io.BytesIO(original.data)) as camera:
        exif = camera.info["exif"]
        edited = np.asarray(camera.convert("RGB")).copy()
    edited[200:330, 520:720] = np.asarray(photo(source="87_OSError.jpg", size=(200, 130)))
    _, checks = _run(evidence_from(jpeg(Image.fromarray(edited), exif, quality=95), tmp_path, "edited.jpg"))
    assert checks["thumbnail"]["outcome"] == "suspicious", checks["thumbnail"]


def test_turned_after_capture_is_a_note_unless_also_edited(tmp_path):
    """A viewer turned the pixels and kept the EXIF: a note; a paste into the turned picture is still found."""
    img = photo()
    turned = Image.fromarray(np.rot90(np.asarray(img)))
    _, checks = _run(_camera_file(tmp_path, img=turned, thumb_img=img))
    assert checks["thumbnail"]["outcome"] == "note" and "turned" in checks["thumbnail"]["observation"]
    assert checks["dimensions"]["outcome"] == "note"
    edited = np.asarray(turned).copy()
    edited[300:420, 100:260] = np.asarray(photo(source="87_OSError.jpg", size=(160, 120)))
    _, checks = _run(_camera_file(tmp_path, img=Image.fromarray(edited), thumb_img=img))
    assert checks["thumbnail"]["outcome"] == "suspicious" and "turned back" in checks["thumbnail"]["observation"]


def test_cropped_after_capture(tmp_path):
    img = photo()
    block = with_thumbnail(exif_bytes(**{**CAMERA, "exif_width": 640, "exif_height": 480}), camera_thumbnail(img))
    evidence = evidence_from(jpeg(img.crop((0, 0, 480, 480)), block), tmp_path)
    _, checks = _run(evidence)
    assert checks["dimensions"]["outcome"] == "suspicious" and "cropped" in checks["dimensions"]["observation"]
    assert checks["thumbnail"]["outcome"] == "suspicious" and "aspect ratio" in checks["thumbnail"]["observation"]


def test_no_exif_at_all(tmp_path):
    result, checks = _run(evidence_from(jpeg(photo()), tmp_path))
    assert checks["exif_present"]["outcome"] == "note" and "strip" in checks["exif_present"]["observation"]
    # Nothing applicable is left: no metadata to judge by.
    assert result.status is Status.INCONCLUSIVE
    for key in ("software", "datetime", "dimensions", "thumbnail", "lens"):
        assert checks[key]["outcome"] == "not available"


def test_real_files(data_dir):
    from forensics_core.evidence import load_evidence

    expected = {
        "Canon_40D.jpg": {"software": "suspicious", "datetime": "suspicious", "quantisation": "suspicious",
                          "thumbnail": "consistent", "lens": "not available"},
        "BlueSquare.jpg": {"software": "suspicious", "exif_present": "note"},
        # Lightroom saved its metadata (XMP history: changed "/metadata"), the pixels are the camera's.
        "87_OSError.jpg": {"software": "note", "datetime": "consistent", "dimensions": "consistent",
                           "quantisation": "consistent", "thumbnail": "note"},
        "canon_hdr_NO.jpg": {"dimensions": "consistent", "thumbnail": "consistent", "quantisation": "consistent"},
        "35-empty.jpg": {"thumbnail": "suspicious", "dimensions": "consistent", "software": "consistent"},
        "nikon-e950.jpg": {"dimensions": "suspicious", "thumbnail": "consistent", "lens": "not available"},
    }
    for name, outcomes in expected.items():
        _, checks = _run(load_evidence(data_dir / "exif" / name))
        for key, outcome in outcomes.items():
            assert checks[key]["outcome"] == outcome, (name, checks[key])


HOSTILE_SOFTWARE = '<script>alert("x")</script><img src=x onerror=1>'


@pytest.mark.parametrize("lie", [{"offset": 10**9}, {"length": 10**9}, {"offset": 8, "length": 64},
                                 {"ifd1_offset": 10**6}])
def test_hostile_exif(tmp_path, lie):
    block = with_thumbnail(exif_bytes(**{**CAMERA, "software": HOSTILE_SOFTWARE}), camera_thumbnail(photo()), **lie)
    evidence = evidence_from(jpeg(photo(), block), tmp_path)
    result, checks = _run(evidence)
    assert checks["thumbnail"]["outcome"] == "note" and checks["software"]["outcome"] == "note"
    assert result.status is Status.OK


def test_malformed_marker_segment_in_the_bytes():
    pixels = np.asarray(photo((64, 48)))
    data = b"\xff\xd8\xff\xe1\x7f\xffExif\x00\x00MM\x00*" + b"\x00" * 20
    evidence = fake_evidence(data, pixels, info(64, 48, make="Canon", model="X"))
    _, checks = _run(evidence)
    assert checks["thumbnail"]["outcome"] == "note" and "past the end" in checks["thumbnail"]["observation"]


def _png(img: Image.Image, **save) -> bytes:
    buf = io.BytesIO()
    img.save(buf, "PNG", **save)
    return buf.getvalue()


@pytest.mark.parametrize("make", [
    lambda: jpeg(Image.new("RGB", (1, 1), (9, 9, 9)), exif_bytes(make="Canon", exif_width=1, exif_height=1)),
    lambda: jpeg(photo((7, 9)), with_thumbnail(exif_bytes(**CAMERA), camera_thumbnail(photo(), (5, 7)))),
    lambda: jpeg(photo().convert("L"), with_thumbnail(exif_bytes(**CAMERA), camera_thumbnail(photo()))),
    lambda: _png(Image.fromarray((np.arange(48 * 64).reshape(48, 64) * 20).astype(np.uint16))),
    lambda: _png(photo((64, 48)).convert("RGBA"), exif=exif_bytes(make="Canon", model="Canon PowerShot SX60 HS")),
    lambda: _png(photo((64, 48)).convert("P")),
    lambda: jpeg(Image.new("RGB", (64, 48), (128, 128, 128)), with_thumbnail(exif_bytes(**CAMERA),
                 camera_thumbnail(Image.new("RGB", (64, 48), (128, 128, 128))))),
])
def test_odd_images_never_raise(tmp_path, make):
    result, _ = _run(evidence_from(make(), tmp_path, "odd.bin"))
    assert result.status in (Status.OK, Status.INCONCLUSIVE)


def test_png_without_metadata_is_inconclusive(tmp_path):
    result, _ = _run(evidence_from(_png(photo((64, 48)).convert("P")), tmp_path, "p.png"))
    assert result.status is Status.INCONCLUSIVE and result.score is None


def test_deterministic(tmp_path):
    evidence = _camera_file(tmp_path, software="GIMP 2.10")
    a, _ = _run(evidence)
    b, _ = _run(evidence)
    a.details.pop("elapsed_s"), b.details.pop("elapsed_s")
    assert json.dumps(check_result(a).details, sort_keys=True) == json.dumps(check_result(b).details, sort_keys=True)
    assert not evidence.pixels.flags.writeable


def _host():
    host = PluginHost(allow=None, deny=())
    host.add(plugin, "metadata")
    return host


def test_report_section_escapes_evidence_text(tmp_path):
    evidence = _camera_file(tmp_path, software=HOSTILE_SOFTWARE)
    host = _host()
    findings = analyze_evidence(evidence, host, Options(detectors=[NAME], isolation="inline"))
    finding = findings.detectors[0]
    assert finding.status is Status.OK and finding.error is None
    section = section_for(host, finding, evidence)
    assert section.failure is None, section.failure
    html = str(section.body)
    assert "<script>" not in html and "&lt;script&gt;" in html
    assert "never proof on its own" in html and "CC BY-SA 3.0" in html
    # The lens figure shows lensfun's prediction even without a measurement.
    assert {f.key for f in section.figures} == {"thumbnail", "lens"}
    assert all(f.used for f in section.figures)


def test_report_section_with_the_lens_comparison(data_dir):
    from forensics_core.evidence import load_evidence
    from forensics_plugins.lens_distortion import plugin as lens_plugin

    evidence = load_evidence(data_dir / "exif" / "87_OSError.jpg")
    host = _host()
    host.add(lens_plugin, "lens_distortion")
    findings = analyze_evidence(evidence, host, Options(detectors=[NAME, "lens_distortion"], isolation="inline"))
    finding = {f.name: f for f in findings.detectors}[NAME]
    lens = finding.details["lens"]
    assert lens["k1_measured"] is not None and lens["outcome"] in ("agrees", "disagrees")
    section = section_for(host, finding, evidence)
    assert section.failure is None and {f.key for f in section.figures} == {"lens"}
    assert "Nikkor 18-70mm" in str(section.body)


def test_no_section_without_details():
    from forensics_core import DetectorFinding

    failed = DetectorFinding(name=NAME, version="1.0.0", plugin="metadata", status=Status.ERROR, summary="failed",
                             score=None, p_value=None, nfa=None, details={}, parameters={}, elapsed_s=0.0, error="x")
    assert Metadata().report_section(failed, None) is None


def test_what_pillow_tolerates_in_the_exif_is_noted_not_printed(tmp_path):
    import subprocess
    import sys

    block = with_thumbnail(exif_bytes(**CAMERA), camera_thumbnail(photo()), ifd1_offset=10**6)
    path = tmp_path / "lie.jpg"
    path.write_bytes(jpeg(photo(), block))
    done = subprocess.run([sys.executable, "-m", "forensics_core", "analyze", str(path), "--out", str(tmp_path / "o"),
                           "--format", "json", "--detectors", "metadata"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and done.stderr.strip() == "", done.stderr
    note = json.loads((tmp_path / "o" / "lie" / "findings.json").read_text())["evidence"]["decoder_note"]
    assert note.startswith("The decoder tolerated: ") and "Corrupt EXIF data" in note
