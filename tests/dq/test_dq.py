"""dq on photos made here: saved twice, with and without a piece pasted between the saves, and saved once."""

import numpy as np
import pytest

from forensics_core import Status, load_evidence
from forensics_plugins.dq.detector import DoubleQuantisation, regions_mask
from forensics_plugins.dq.spec import DEFAULT_PARAMS
from forensics_plugins.dq.synth import decode, encode, paste, scene, synthetic_cases


def _evidence(tmp_path, name, data):
    path = tmp_path / name
    path.write_bytes(data)
    return load_evidence(path)


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("dq")
    return [(case, DoubleQuantisation().analyze(_evidence(tmp, case.name + case.suffix, case.data), DEFAULT_PARAMS))
            for case in synthetic_cases(3, 8)]


def test_pasted_pieces_lack_the_earlier_quantisation_and_double_saved_originals_do_not(results):
    spliced = [r for c, r in results if c.spliced]
    twice = [r for c, r in results if not c.spliced and c.conditions["saves"] == "2"]
    assert all(r.status is Status.OK for r in spliced + twice), [r.summary for r in spliced + twice]
    assert all(r.p_value is None for r in spliced + twice)
    # A never-compressed piece in a photo saved at quality 95 can be too faint to see (measured: 2 of 8).
    assert sum(r.score > 0.5 for r in spliced) >= 6, [r.score for r in spliced]
    assert max(r.score for r in twice) < 0.1, [r.score for r in twice]


def test_a_photo_saved_once_says_nothing(results):
    once = [r for c, r in results if c.conditions["saves"] == "1"]
    assert once and all(r.status is Status.INCONCLUSIVE and r.score is None for r in once)
    assert all("no earlier JPEG quantisation" in r.summary for r in once)


def test_the_flagged_windows_cover_the_pasted_piece(results):
    for case, r in results:
        if case.spliced and r.score > 0.5:
            mask = regions_mask(r.details, case.mask.shape)
            covered = (mask & case.mask).sum() / case.mask.sum()
            b = r.details["best"]
            best = case.mask[8 * b["row"]:8 * (b["row"] + b["size"]), 8 * b["col"]:8 * (b["col"] + b["size"])]
            assert covered > 0.5 and best.mean() > 0.3, (case.name, covered, best.mean())


def test_same_photo_same_findings(tmp_path):
    rng = np.random.default_rng(4)
    spliced, _ = paste(decode(encode(scene(rng, (640, 480)), 75)), rng, "raw")
    data = encode(spliced, 95)
    a = DoubleQuantisation().analyze(_evidence(tmp_path, "a.jpg", data), DEFAULT_PARAMS)
    b = DoubleQuantisation().analyze(_evidence(tmp_path, "b.jpg", data), DEFAULT_PARAMS)
    a.details.pop("elapsed_s"), b.details.pop("elapsed_s")
    assert (a.score, a.details) == (b.score, b.details)


def test_a_png_is_skipped_with_the_reason_and_a_jpeg_gets_its_report_section(tmp_path):
    from PIL import Image

    from forensics_core.analysis import Options, analyze_evidence
    from forensics_core.plugins import PluginHost
    from forensics_core.report.plugin_sections import section_for

    host = PluginHost.from_entry_points(allow=["dq"])
    assert host.detectors["dq"].spec.calibrated_on == "score"
    rng = np.random.default_rng(6)
    spliced, _ = paste(decode(encode(scene(rng, (640, 480)), 70)), rng, "shifted_jpeg")
    jpeg = _evidence(tmp_path, "spliced.jpg", encode(spliced, 92))
    (finding,) = analyze_evidence(jpeg, host, Options(detectors=["dq"], isolation="process")).detectors
    assert finding.status is Status.OK and finding.score > 0.25, finding.error or finding.summary
    section = section_for(host, finding, jpeg)
    assert section.failure is None
    body = str(section.body)
    for text in ("Earlier quantisation", "Windows lacking", "Strength and limits", "Bianchi", "processed locally"):
        assert text in body, text
    assert [f.key for f in section.figures] == ["votes"] and section.figures[0].used

    once = _evidence(tmp_path, "once.jpg", encode(scene(rng, (640, 480)), 92))
    (inconclusive,) = analyze_evidence(once, host, Options(detectors=["dq"])).detectors
    assert inconclusive.status is Status.INCONCLUSIVE
    plain = section_for(host, inconclusive, once)
    assert plain.failure is None and "no window was tested" in str(plain.body)

    Image.fromarray(np.round(spliced).astype(np.uint8)).save(tmp_path / "spliced.png")
    png = load_evidence(tmp_path / "spliced.png")
    (skipped,) = analyze_evidence(png, host, Options(detectors=["dq"])).detectors
    assert skipped.status is Status.SKIPPED and "PNG" in skipped.summary
