"""The plugin through the host: registration, analysis in a child, report section, localisation, cases."""

import io

import numpy as np
import pytest
from PIL import Image

from forensics_core import Status, SyntheticCase, load_evidence
from forensics_core.analysis import Options, analyze_evidence
from forensics_core.plugins import PluginHost
from forensics_core.report.plugin_sections import section_for
from forensics_plugins.cfa import synth
from forensics_plugins.cfa.figures import MAP_MAX_SIDE


@pytest.fixture(scope="module")
def host():
    return PluginHost.from_entry_points(allow=["cfa"])


def _run(host, path, isolation="inline"):
    ev = load_evidence(path)
    findings = analyze_evidence(ev, host, Options(detectors=["cfa"], isolation=isolation))
    return ev, findings.detectors[0]


def test_plugin_registers_the_detector(host):
    assert "cfa" in host.detectors
    assert host.detectors["cfa"].spec.default_params["nfa_threshold"] == 0.01


def test_section_of_a_spliced_photo(host, tmp_path):
    _, spliced = synth.make_pair(4, (384, 512), algorithm="hamilton_adams", shift=(1, 0), fraction=0.2)
    path = tmp_path / "spliced.png"
    path.write_bytes(synth.encode(spliced.rgb)[0])
    ev, finding = _run(host, path, isolation="process")
    assert finding.status is Status.OK, finding.error or finding.summary
    assert finding.details["regions"] and finding.nfa < 0.01
    section = section_for(host, finding, ev)
    assert section.failure is None and section.body is not None
    body = str(section.body)
    for text in ("The photo's mosaic", "The test", "Regions", "Method and limitations", "Popescu",
                 "green on the other diagonal", "NFA"):
        assert text in body, text
    assert [f.key for f in section.figures] == ["map"] and section.figures[0].used
    img = Image.open(io.BytesIO(section.files["cfa-map.png"][0]))
    assert max(img.size) <= MAP_MAX_SIDE

    mask = host.detectors["cfa"].detector.localize(finding, spliced.mask.shape)
    iou = (mask & spliced.mask).sum() / (mask | spliced.mask).sum()
    print(f"localisation of a 20% region: IoU {iou:.2f}")
    assert iou > 0.5


def test_section_of_an_inconclusive_photo_gives_the_reason(host, tmp_path):
    path = tmp_path / "grey.png"
    Image.fromarray(np.random.default_rng(0).integers(0, 256, (128, 128), dtype=np.uint8)).save(path)
    ev, finding = _run(host, path)
    assert finding.status is Status.INCONCLUSIVE
    section = section_for(host, finding, ev)
    assert section.failure is None
    assert "greyscale" in str(section.body) and not section.figures


def test_palette_photo(host, tmp_path):
    _, spliced = synth.make_pair(4, (256, 256))
    path = tmp_path / "palette.png"
    Image.fromarray(spliced.rgb).convert("P", palette=Image.Palette.ADAPTIVE).save(path)
    _, finding = _run(host, path)
    assert finding.status in (Status.INCONCLUSIVE, Status.OK) and finding.error is None


def test_synthetic_cases_are_deterministic_and_tagged(host):
    a = list(host.detectors["cfa"].detector.synthetic_cases(3, 2))
    b = list(synth.synthetic_cases(3, 2))
    assert len(a) == 4 and all(isinstance(c, SyntheticCase) for c in a)
    assert [c.data for c in a] == [c.data for c in b]
    assert len({c.name for c in a}) == 4
    for case in a:
        img = Image.open(io.BytesIO(case.data))
        assert abs(img.width * img.height - 1_000_000) < 100_000
        assert case.spliced == (case.conditions["kind"] != "none")
        if case.spliced:
            assert case.mask.shape == (img.height, img.width) and 0.08 < case.mask.mean() < 0.32
        assert {"kind", "demosaic", "jpeg_quality", "resize", "shift", "donor", "size"} <= set(case.conditions)
