"""The XMP creator tool and history, and the measured rates the report quotes."""

import subprocess
import sys
from pathlib import Path

from forensics_plugins.metadata.real_rates import corpus_sentence, measured_rates, rate_sentence
from forensics_plugins.metadata.xmp import xmp_agents
from metadata_helpers import exif_bytes, jpeg, photo

PACKET = b"""<?xpacket begin="" id="W5M0MpCehiHzreSzNTczkc9d"?>
<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#">
<rdf:Description rdf:about="" xmlns:xmp="http://ns.adobe.com/xap/1.0/"
  xmlns:xmpMM="http://ns.adobe.com/xap/1.0/mm/" xmlns:stEvt="http://ns.adobe.com/xap/1.0/sType/ResourceEvent#"
  xmp:CreatorTool="Adobe Photoshop 25.0 (Windows)">
<xmpMM:History><rdf:Seq>
<rdf:li stEvt:action="saved" stEvt:softwareAgent="GIMP 2.10" stEvt:changed="/"/>
<rdf:li><stEvt:softwareAgent>Adobe Photoshop Lightroom Classic 12.0 &amp; more</stEvt:softwareAgent></rdf:li>
<rdf:li stEvt:action="saved" stEvt:softwareAgent="GIMP 2.10" stEvt:changed="/"/>
</rdf:Seq></xmpMM:History></rdf:Description></rdf:RDF></x:xmpmeta><?xpacket end="w"?>"""


def test_creator_tool_and_history_are_read():
    data = jpeg(photo((64, 48)), exif_bytes(make="Canon"), xmp=PACKET)
    assert xmp_agents(data) == [("creator", "Adobe Photoshop 25.0 (Windows)"), ("history", "GIMP 2.10"),
                                ("history", "Adobe Photoshop Lightroom Classic 12.0 & more")]


def test_no_xmp_or_not_an_image():
    assert xmp_agents(jpeg(photo((64, 48)))) == []
    assert xmp_agents(b"\xff\xd8 not really") == []


def test_an_editor_in_the_xmp_is_flagged(tmp_path):
    from forensics_plugins.metadata.detector import Metadata
    from forensics_plugins.metadata.spec import DEFAULT_PARAMS
    from metadata_helpers import evidence_from

    evidence = evidence_from(jpeg(photo(), exif_bytes(make="Canon", software="Ver.1.00"), xmp=PACKET), tmp_path)
    checks = {c["id"]: c for c in Metadata().analyze(evidence, DEFAULT_PARAMS, {}).details["checks"]}
    assert checks["software"]["outcome"] == "suspicious" and "CreatorTool" in checks["software"]["observation"]


def test_shipped_rates_are_quoted():
    rates = measured_rates()
    assert rates is not None and rates["n_photos"] > 0
    for check_id, row in rates["checks"].items():
        assert 0 <= row["suspicious"] <= row["applicable"] <= rates["n_photos"]
        # The acceptance bound of every check on camera originals.
        assert row["suspicious"] <= 0.02 * rates["n_photos"], check_id
    assert "camera originals" in rate_sentence("thumbnail") and "95% confidence" in rate_sentence("thumbnail")
    assert rates["measured"] in corpus_sentence()
    assert rate_sentence("no such check") is None


def test_benchmark_without_the_corpus(tmp_path):
    script = Path(__file__).resolve().parents[2] / "benchmarks" / "metadata_real.py"
    out = subprocess.run([sys.executable, str(script), str(tmp_path / "absent")], capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0 and "absent" in out.stdout


_ONE_TOKEN = """
import io, sys
from PIL import Image, PngImagePlugin
from forensics_plugins.metadata.xmp import xmp_agents
info = PngImagePlugin.PngInfo()
info.add_itxt("XML:com.adobe.xmp", "a" * 300_000 + ' xmp:CreatorTool="GIMP 2.10"')
buf = io.BytesIO()
Image.new("RGB", (16, 16)).save(buf, "PNG", pnginfo=info)
print(xmp_agents(buf.getvalue()))
"""


def test_one_long_token_in_the_xmp_is_read_in_linear_time():
    # 300 KB of one word took over a minute with a regular expression that backtracked at every position;
    # read in linear time it takes milliseconds, so a minute's bound is no timing measurement.
    out = subprocess.run([sys.executable, "-c", _ONE_TOKEN], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[('creator', 'GIMP 2.10')]"


def test_the_users_pixel_limit_reaches_the_xmp_reader():
    # The header claims 16000 x 16000 (256 MP), beyond Pillow's default bomb limit (179 MP); only the
    # header is read.
    import contextlib

    from PIL import Image

    data = bytearray(jpeg(photo((64, 48)), exif_bytes(make="Canon"), xmp=PACKET))
    sof = data.find(b"\xff\xc0")
    data[sof + 5: sof + 9] = (16000).to_bytes(2, "big") * 2

    @contextlib.contextmanager
    def limit():
        before = Image.MAX_IMAGE_PIXELS
        Image.MAX_IMAGE_PIXELS = 300_000_000
        try:
            yield
        finally:
            Image.MAX_IMAGE_PIXELS = before

    assert xmp_agents(bytes(data)) == []
    assert xmp_agents(bytes(data), limit)[0] == ("creator", "Adobe Photoshop 25.0 (Windows)")
