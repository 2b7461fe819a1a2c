"""The metadata check, its figure and the report all use the thumbnail the intake decoded, once."""

import dataclasses

import pytest

from forensics_core import thumbnail as core_thumbnail
from forensics_core.analysis import Options, analyze_evidence
from forensics_core.plugins import PluginHost
from forensics_core.report import images
from forensics_core.report.plugin_sections import section_for
from forensics_core.report.render import ReportOptions, SignatureInfo, render_html
from forensics_core.thumbnail import read_thumbnail
from forensics_plugins.metadata import plugin
from forensics_plugins.metadata.spec import NAME
from metadata_helpers import camera_thumbnail, evidence_from, exif_bytes, jpeg, photo, with_thumbnail

CAMERA = dict(make="Canon", model="Canon PowerShot SX60 HS", datetime="2021:06:01 12:00:00",
              datetime_original="2021:06:01 12:00:00", orientation=1, exif_width=640, exif_height=480)
SIGNATURE = SignatureInfo("A. Examiner", "Lab", "CN=A. Examiner", "AA:BB", True, "2024-01-01T00:00:00Z",
                          "2026-01-01T00:00:00Z")


def _host() -> PluginHost:
    host = PluginHost(allow=None, deny=())
    host.add(plugin, "metadata")
    return host


def _finding_section_and_report(evidence):
    host = _host()
    findings = analyze_evidence(evidence, host, Options(detectors=[NAME], isolation="inline"))
    finding = findings.detectors[0]
    section = section_for(host, finding, evidence)
    report = render_html(findings, evidence, SIGNATURE, ReportOptions(exhibit_id="E-1"), host=host,
                         sections=[section])
    return finding, section, report


def test_one_decode_serves_the_check_its_figure_and_the_report(tmp_path, monkeypatch):
    calls = []
    original = core_thumbnail.decode
    monkeypatch.setattr(core_thumbnail, "decode", lambda blob, max_pixels: calls.append(1) or original(blob, max_pixels))
    img = photo()
    evidence = evidence_from(jpeg(img, with_thumbnail(exif_bytes(**CAMERA), camera_thumbnail(img))), tmp_path)
    assert len(calls) == 1 and evidence.thumbnail.size == (160, 120)

    finding, section, report = _finding_section_and_report(evidence)
    assert len(calls) == 1
    checks = {c["id"]: c for c in finding.details["checks"]}
    assert checks["thumbnail"]["outcome"] == "consistent"
    details = finding.details["thumbnail"]
    assert details["present"] and (details["width"], details["height"]) == evidence.thumbnail.size
    assert {f.key for f in section.figures} >= {"thumbnail"} and section.failure is None
    # The report shows the intake's decoded pixels, re-encoded.
    assert images.data_url(images.thumbnail_jpeg(evidence.thumbnail), "image/jpeg") in report.html


def test_the_check_reads_the_evidences_thumbnail_not_the_bytes(tmp_path):
    img = photo()
    evidence = evidence_from(jpeg(img, with_thumbnail(exif_bytes(**CAMERA), camera_thumbnail(img))), tmp_path)
    other = photo(source="35-empty.jpg")
    swapped = dataclasses.replace(evidence, thumbnail=read_thumbnail(
        jpeg(other, with_thumbnail(exif_bytes(**CAMERA), camera_thumbnail(other))), "JPEG"))
    finding, _, _ = _finding_section_and_report(swapped)
    checks = {c["id"]: c for c in finding.details["checks"]}
    assert checks["thumbnail"]["outcome"] == "suspicious"
    assert finding.details["thumbnail"]["correlation"] < 0.9


@pytest.mark.parametrize("lie, message", [
    ({"offset": 10**7}, "IFD1 places the thumbnail at bytes 10000000-"),
    ({"length": 0}, "IFD1 points to a thumbnail of 0 bytes"),
])
def test_malformed_ifd1_intake_succeeds_and_the_check_notes_it(tmp_path, lie, message):
    img = photo()
    evidence = evidence_from(jpeg(img, with_thumbnail(exif_bytes(**CAMERA), camera_thumbnail(img), **lie)), tmp_path)
    error = evidence.thumbnail.error
    assert error.startswith(message) and evidence.thumbnail.pixels is None and evidence.pixels.shape == (480, 640, 3)

    finding, section, report = _finding_section_and_report(evidence)
    checks = {c["id"]: c for c in finding.details["checks"]}
    assert checks["thumbnail"]["outcome"] == "note"
    assert checks["thumbnail"]["observation"] == f"The EXIF names a thumbnail that cannot be used: {error}."
    assert finding.details["thumbnail"]["error"] == error and not finding.details["thumbnail"]["present"]
    assert "thumbnail" not in {f.key for f in section.figures}
    assert "Thumbnail embedded in the EXIF data" not in report.html
    assert f"could not be read: {error}." in " ".join(report.html.split())


def test_the_checks_limits_apply_to_the_intakes_thumbnail(tmp_path):
    img = photo()
    blob = camera_thumbnail(img)
    evidence = evidence_from(jpeg(img, with_thumbnail(exif_bytes(**CAMERA), blob)), tmp_path)
    host = _host()
    findings = analyze_evidence(evidence, host, Options(detectors=[NAME], isolation="inline",
                                                        detector_params={NAME: {"thumbnail_max_pixels": 100}}))
    finding = findings.detectors[0]
    checks = {c["id"]: c for c in finding.details["checks"]}
    assert checks["thumbnail"]["outcome"] == "note"
    assert "the thumbnail claims 160 x 120 pixels, outside the accepted 1 to 100" in checks["thumbnail"]["observation"]
    assert "thumbnail" not in {f.key for f in section_for(host, finding, evidence).figures}
