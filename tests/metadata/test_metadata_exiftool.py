"""Metadata read by ExifTool itself (MakerNotes, XMP, IPTC), the Pillow fallback, and text decoded correctly."""

import shutil
import subprocess

import pytest

from forensics_core import EvidenceError, exiftool, load_evidence
from forensics_plugins.metadata.detector import Metadata
from forensics_plugins.metadata.spec import DEFAULT_PARAMS
from metadata_helpers import evidence_from, exif_bytes, jpeg, photo

XMP = b"""<?xpacket begin="" id="W5M0MpCehiHzreSzNTczkc9d"?>
<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#">
<rdf:Description rdf:about="" xmlns:exif="http://ns.adobe.com/exif/1.0/"
  xmlns:photoshop="http://ns.adobe.com/photoshop/1.0/" xmlns:xmp="http://ns.adobe.com/xap/1.0/"
  exif:DateTimeOriginal="%s" xmp:CreateDate="%s">
<photoshop:DocumentAncestors><rdf:Bag><rdf:li>xmp.did:0a1b2c3d</rdf:li><rdf:li>uuid:5E6F</rdf:li></rdf:Bag>
</photoshop:DocumentAncestors>
</rdf:Description></rdf:RDF></x:xmpmeta><?xpacket end="w"?>"""


@pytest.fixture
def no_exiftool(monkeypatch, tmp_path):
    monkeypatch.setenv("PATH", str(tmp_path))


def _checks(evidence):
    return {c["id"]: c for c in Metadata().analyze(evidence, DEFAULT_PARAMS, {}).details["checks"]}


def _installed_version() -> str:
    return subprocess.run(["exiftool", "-ver"], capture_output=True, text=True, check=True).stdout.strip()


def test_exiftool_reads_makernotes_xmp_and_iptc_from_the_hashed_bytes(data_dir):
    info = load_evidence(data_dir / "exif" / "87_OSError.jpg").info
    assert info.metadata_reader.startswith(f"ExifTool {_installed_version()} (-json -G1 -a -u -n)")
    groups = {t.group for t in info.metadata}
    assert {"IFD0", "ExifIFD", "Nikon", "IPTC", "XMP-xmpMM", "XMP-photoshop"} <= groups
    assert not groups & {"System", "ExifTool"}, "ExifTool's own and the stdin pseudo-file's tags are not evidence"
    tags = {(t.group, t.name): t.value for t in info.metadata}
    assert tags[("IFD0", "Model")] == "NIKON D70s"


def test_without_exiftool_pillow_reads_the_exif_and_says_so(data_dir, no_exiftool):
    info = load_evidence(data_dir / "exif" / "87_OSError.jpg").info
    assert info.metadata == []
    assert info.metadata_reader.startswith("Pillow") and "ExifTool is not installed" in info.metadata_reader
    assert info.exif.model == "NIKON D70s" and info.exif.raw
    checks = _checks(load_evidence(data_dir / "exif" / "87_OSError.jpg"))
    assert {checks[k]["outcome"] for k in ("xmp_dates", "ancestors", "serial", "previews")} == {"not available"}


def test_a_hung_exiftool_is_stopped_at_its_time_limit(data_dir):
    found = exiftool.read((data_dir / "exif" / "Canon_40D.jpg").read_bytes(), timeout_s=0.001)
    assert found.tags == [] and "did not finish within" in found.error


def test_utf8_text_is_decoded_and_a_right_to_left_override_is_shown_not_obeyed(tmp_path):
    data = jpeg(photo((64, 48)), exif_bytes(make="CafXX", software="PhotoXXXgpj.exe"))
    data = data.replace(b"CafXX", b"Caf\xc3\xa9").replace(b"PhotoXXXgpj", b"Photo\xe2\x80\xaegpj")
    info = evidence_from(data, tmp_path).info
    assert info.exif.make == "Café"
    assert info.exif.software == "Photo\\u202egpj.exe"
    tags = {(t.group, t.name): t.value for t in info.metadata}
    assert tags[("IFD0", "Software")] == "Photo\\u202egpj.exe" and tags[("IFD0", "Make")] == "Café"


def test_xmp_dates_and_placed_documents(tmp_path):
    exif = exif_bytes(make="Canon", datetime_original="2020:01:02 10:00:00")
    agreeing = jpeg(photo(), exif, xmp=XMP % (b"2020-01-02T10:00:00", b"2020-01-02T09:00:00Z"))
    checks = _checks(evidence_from(agreeing, tmp_path, "a.jpg"))
    assert checks["xmp_dates"]["outcome"] == "consistent", checks["xmp_dates"]
    assert "time-zone offset" in checks["xmp_dates"]["observation"]
    assert checks["ancestors"]["outcome"] == "suspicious" and "2 document(s)" in checks["ancestors"]["observation"]

    rewritten = jpeg(photo(), exif, xmp=XMP % (b"2020-01-05T18:30:00", b"2020-01-05T18:30:00"))
    checks = _checks(evidence_from(rewritten, tmp_path, "b.jpg"))
    assert checks["xmp_dates"]["outcome"] == "suspicious" and "rewritten" in checks["xmp_dates"]["observation"]


def test_makernote_serial_against_exif(data_dir):
    checks = _checks(load_evidence(data_dir / "exif" / "canon_hdr_NO.jpg"))
    assert checks["serial"]["outcome"] in ("consistent", "not available")
    assert checks["previews"]["outcome"] in ("note", "not available")


def test_the_report_appendix_counts_exiftool_groups_and_every_tag_is_beside_it(data_dir, tmp_path):
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "forensics_core", "analyze", str(data_dir / "exif" / "87_OSError.jpg"),
                           "--out", str(tmp_path), "--detectors", "metadata", "--format", "html"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    (report,) = tmp_path.rglob("report.html")
    html = report.read_text(encoding="utf-8")
    assert "Appendix C. Metadata (ExifTool)" in html and "Nikon " in html and "Metadata read by" in html
    groups = {line.split(",", 1)[0] for line in (report.parent / "metadata.csv").read_text(encoding="utf-8").splitlines()[1:]}
    assert {"IFD0", "ExifIFD", "Nikon"} <= groups


@pytest.mark.skipif(shutil.which("exiftool") is None, reason="needs ExifTool")
def test_the_version_stated_is_the_one_installed(data_dir):
    found = exiftool.read((data_dir / "exif" / "Canon_40D.jpg").read_bytes())
    assert found.error is None and found.version == _installed_version()


@pytest.mark.skipif(shutil.which("exiftool") is None, reason="needs ExifTool")
def test_exiftool_runs_while_the_photo_is_decoded_and_a_refused_photo_stops_it(data_dir, tmp_path, monkeypatch):
    data = (data_dir / "exif" / "Canon_40D.jpg").read_bytes()
    assert exiftool.start(data).result() == exiftool.read(data)
    started = []
    real_start = exiftool.start

    def start(data):
        reading = real_start(data)
        started.append(reading._process)
        return reading

    monkeypatch.setattr(exiftool, "start", start)
    assert load_evidence(data_dir / "exif" / "Canon_40D.jpg").info.metadata
    (tmp_path / "notes.jpg").write_bytes(b"not a photo at all")
    with pytest.raises(EvidenceError, match="not an image"):
        load_evidence(tmp_path / "notes.jpg")
    assert len(started) == 2 and all(process.returncode is not None for process in started)
