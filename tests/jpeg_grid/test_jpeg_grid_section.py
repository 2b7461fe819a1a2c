"""The report section, rendered as the report renders it, and the plugin's hooks through the host."""

import io

import numpy as np
import pytest
from PIL import Image

from forensics_core import Status, load_evidence
from forensics_core.analysis import Options, analyze_evidence
from forensics_core.plugins import PluginHost
from forensics_core.report.plugin_sections import section_for
from forensics_plugins.jpeg_grid import synth
from forensics_plugins.jpeg_grid.figures import MAP_MAX_SIDE


@pytest.fixture(scope="module")
def host():
    return PluginHost.from_entry_points(allow=["jpeg_grid"])


def _run(host, path):
    ev = load_evidence(path)
    findings = analyze_evidence(ev, host, Options(detectors=["jpeg_grid"], isolation="inline"))
    return ev, findings.detectors[0]


def test_plugin_registers_the_detector(host):
    assert "jpeg_grid" in host.detectors
    spec = host.detectors["jpeg_grid"].spec
    assert spec.version == "2.6.0" and len(spec.references) >= 2
    assert spec.default_params["nfa_threshold"] == 1.0


def test_section_of_a_spliced_photo_has_map_regions_test_method_and_limitations(host, tmp_path):
    case = synth.make_spliced(3, "splice", size=(384, 512), final_quality=99, shift=(5, 2))
    path = tmp_path / "spliced.jpg"
    path.write_bytes(case.data)
    ev, finding = _run(host, path)
    assert finding.status is Status.OK, finding.error or finding.summary
    section = section_for(host, finding, ev)
    assert section.failure is None and section.body is not None
    body = str(section.body)
    for text in ("Main grid", "Regions on another grid", "The test", "Method and limitations", "(5, 2)",
                 "Nikoukhah", "meaningful"):
        assert text in body, text
    keys = {f.key for f in section.figures}
    assert keys == {"map", "votes"} and all(f.used for f in section.figures)
    overlay = Image.open(io.BytesIO(section.files["jpeg_grid-map.png"][0]))
    assert max(overlay.size) <= MAP_MAX_SIDE


def test_section_of_a_never_compressed_photo_says_inconclusive(host, tmp_path):
    data, _ = synth.make_never_compressed(1, size=(256, 320))
    path = tmp_path / "never.png"
    path.write_bytes(data)
    ev, finding = _run(host, path)
    assert finding.status is Status.INCONCLUSIVE
    section = section_for(host, finding, ev)
    body = str(section.body)
    assert "does not say the photo is authentic" in body
    assert {f.key for f in section.figures} == {"votes"}


def test_tiny_photo_has_no_section_of_its_own(host, tmp_path):
    path = tmp_path / "tiny.png"
    Image.fromarray(np.zeros((5, 5), np.uint8)).save(path)
    ev, finding = _run(host, path)
    assert finding.status is Status.INCONCLUSIVE
    assert section_for(host, finding, ev).body is None


def test_synthetic_cases_through_the_registered_detector(host):
    cases = list(host.detectors["jpeg_grid"].detector.synthetic_cases(1, 2))
    assert len(cases) == 4 and sum(c.spliced for c in cases) == 2
