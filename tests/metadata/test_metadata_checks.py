"""Unit tests of the tag checks: EXIF presence, Software, dates, dimensions."""

import pytest

from forensics_plugins.metadata.checks import (
    camera_name,
    classify_software,
    datetimes,
    dimensions,
    dimensions_changed,
    exif_presence,
    parse_exif_datetime,
    software_tag,
)
from forensics_core.findings import RawTag
from metadata_helpers import info


@pytest.mark.parametrize("text", [
    "Adobe Photoshop CS2 Macintosh", "Adobe Photoshop Elements 7.0", "GIMP 2.4.5",
    "Adobe Photoshop Lightroom 6.0 (Windows)",
    "Snapseed 2.0", "Affinity Photo 1.10", "Paint.NET v3.36", "Pixelmator Pro 2.1", "PicsArt", "PhotoScape",
    "Canva", "Capture One 21 Windows", "darktable 3.8.0",
])
def test_editors_are_named(text):
    assert classify_software(text) == "editor"


@pytest.mark.parametrize("text, make, model", [
    ("Ver.1.00", "NIKON CORPORATION", "NIKON D70s"),
    ("1.00", "CASIO", "EX-Z750"),
    ("v981-79", "NIKON", "E950"),
    ("8.3", "Apple", "iPhone 6"),
    ("Firmware Version 1.0.2", "Canon", "Canon EOS 5D"),
    ("Digital Camera DX-10 Ver1.00", "FUJIFILM", "DX-10"),
    ("V1.0", "Canon", "Canon EOS 5D"),
    ("Firmware 1.02", "SONY", "DSC-RX100"),
    ("v353u-75", "OLYMPUS", "C-750"),
    ("HD7.01.01.90.00", "GoPro", "HERO7 Black"),
    ("N900AUCUCNC2", "samsung", "SAMSUNG-SM-N900A"),
    ("*ist DL     Ver 1.00", "PENTAX Corporation", "PENTAX *ist DL"),
])
def test_firmware_strings(text, make, model):
    assert classify_software(text, make, model) == "firmware"


def test_transfer_tools_and_unknown_programs():
    assert classify_software("Nikon Transfer 1.1 W") == "transfer"
    assert classify_software("MyTool 2.0", "Canon", "Canon EOS 5D") == "unknown"
    # A program named with a version is not firmware unless it is the camera's own name.
    assert classify_software("Digital Camera DX-10 Ver1.00", "Canon", "Canon EOS 5D") == "unknown"
    assert classify_software("<script>alert(1)</script>") == "unknown"
    assert classify_software("Windows 10") == "unknown" and classify_software("Win10") == "unknown"


def test_camera_name_does_not_repeat_the_make():
    assert camera_name("Canon", "Canon EOS 40D") == "Canon EOS 40D"
    assert camera_name("NIKON", "E950") == "NIKON E950"
    assert camera_name(None, "E950") == "E950"


def test_software_outcomes():
    assert software_tag(info(software="GIMP 2.4.5")).outcome == "suspicious"
    # The XMP creator tool made the file; a history entry may be a metadata-only save.
    assert software_tag(info(software="Ver.1.00"), [("creator", "Adobe Photoshop CS2 Macintosh")]).outcome == \
        "suspicious"
    assert software_tag(info(), [("history", "Adobe Photoshop Lightroom 6.0 (Windows)")]).outcome == "note"
    assert software_tag(info(software="Ver.1.00"), [("creator", "NIKON D70 Ver.1.00")]).outcome == "consistent"
    assert software_tag(info(software="Ver.1.00", make="NIKON", model="D70")).outcome == "consistent"
    assert software_tag(info(software="Nikon Transfer 1.1 W")).outcome == "note"
    assert software_tag(info(software="Whatever")).outcome == "note"
    check = software_tag(info(make="Canon"))
    assert check.outcome == "not available"


def test_exif_presence():
    # Platforms strip EXIF from untouched photos: its absence is an observation, not a suspicion.
    assert exif_presence(info(raw=[])).outcome == "note"
    assert exif_presence(info(fmt="MPO", raw=[])).outcome == "note"
    assert exif_presence(info(fmt="PNG", raw=[])).outcome == "note"
    assert exif_presence(info(software="x")).outcome == "note"
    check = exif_presence(info(make="Canon", model="Canon EOS 40D"))
    assert check.outcome == "consistent" and "Canon EOS 40D" in check.observation


def test_parse_exif_datetime():
    assert parse_exif_datetime("2008:05:30 15:56:01").isoformat() == "2008-05-30T15:56:01"
    for bad in ("0000:00:00 00:00:00", "2008:13:01 00:00:00", "2008-05-30", "    :  :     :  :  ", None, "garbage"):
        assert parse_exif_datetime(bad) is None


@pytest.mark.parametrize("modified, original, outcome", [
    ("2020:01:01 10:00:00", "2020:01:01 10:00:00", "consistent"),
    ("2020:01:01 10:00:02", "2020:01:01 10:00:00", "consistent"),
    ("2020:01:01 10:00:03", "2020:01:01 10:00:00", "suspicious"),
    ("2020:03:01 10:00:00", "2020:01:01 10:00:00", "suspicious"),
    ("2019:12:31 10:00:00", "2020:01:01 10:00:00", "suspicious"),
    ("0000:00:00 00:00:00", "2020:01:01 10:00:00", "note"),
    (None, "2020:01:01 10:00:00", "not available"),
])
def test_datetimes(modified, original, outcome):
    check = datetimes(info(datetime=modified, datetime_original=original), tolerance_s=2.0)
    assert check.outcome == outcome
    if outcome == "suspicious":
        assert original in check.observation


def test_datetime_after_a_long_exposure():
    """A 30 s exposure with a 30 s dark frame: the camera writes the file a minute after the shutter opened."""
    def check(modified, exposure):
        raw = [RawTag("Exif", 0x829A, "ExposureTime", exposure)]
        return datetimes(info(datetime=modified, datetime_original="2020:01:01 10:00:00", raw=raw), 2.0).outcome

    assert check("2020:01:01 10:01:01", "30") == "consistent"
    assert check("2020:01:01 10:01:03", "30") == "suspicious"
    assert check("2020:01:01 10:00:03", "0.004") == "suspicious"
    assert check("2020:01:01 10:00:03", "garbage") == "suspicious"


@pytest.mark.parametrize("exif_size, orientation, outcome, changed", [
    ((640, 480), 1, "consistent", False),
    ((480, 640), 6, "consistent", False),
    ((480, 640), 1, "note", False),  # turned after capture: content unchanged
    ((1280, 960), 1, "suspicious", True),
    ((1280, 720), 1, "suspicious", True),
    ((None, None), 1, "not available", None),
    ((0, 0), 1, "not available", None),
])
def test_dimensions(exif_size, orientation, outcome, changed):
    evidence_info = info(640, 480, exif_image_width=exif_size[0], exif_image_height=exif_size[1],
                         orientation=orientation)
    check = dimensions(evidence_info)
    assert check.outcome == outcome
    assert dimensions_changed(evidence_info) is changed
    if exif_size == (1280, 960):
        assert "resized" in check.observation
    if exif_size == (1280, 720):
        assert "cropped" in check.observation
