"""Plugin discovery and failure containment, through real entry points."""

import json
import os
import time
from importlib.metadata import EntryPoint
from pathlib import Path

import pytest
from click.testing import CliRunner
from plugin_hosts import fixture_host

from forensics_core import ENTRY_POINT_GROUP, Status, VerdictLabel, analyze
from forensics_core.cli import cli
from forensics_core.plugins import PluginHost


def by_name(findings):
    return {d.name: d for d in findings.detectors}


def test_bundled_plugins_come_from_the_public_entry_point_group():
    host = PluginHost.from_entry_points(allow=None, deny=())
    record = host.records["lens_distortion"]
    assert record.status == "loaded"
    assert record.distribution == "forensics"
    assert "lens_distortion" in host.detectors


def test_allow_and_deny_lists_from_the_environment(monkeypatch):
    monkeypatch.setenv("FORENSICS_DISABLE_PLUGINS", "lens_distortion")
    host = PluginHost.from_entry_points()
    assert host.records["lens_distortion"].status == "disabled"
    assert "lens_distortion" not in host.detectors
    monkeypatch.delenv("FORENSICS_DISABLE_PLUGINS")
    monkeypatch.setenv("FORENSICS_PLUGINS", "nothing_by_that_name")
    assert PluginHost.from_entry_points().detectors == {}


def test_detectors_are_registered_once_in_the_main_process_when_first_needed(photo):
    import fixture_plugins

    fixture_plugins.REGISTERED.clear()
    host = fixture_host("good", "registering")
    assert fixture_plugins.REGISTERED == []
    first = by_name(analyze(photo, ["good", "registering"], host=host, jobs=2))["registering"]
    again = by_name(analyze(photo, ["registering"], host=host))["registering"]
    assert first.details["registered"] == again.details["registered"] == [os.getpid()]


def test_the_core_calls_the_detector_object_it_registered(photo):
    host = fixture_host("good")
    import fixture_plugins

    assert host.detectors["good"].detector is fixture_plugins.good
    assert host.detectors["good"].plugin == "good"


def test_a_deferred_detector_is_imported_in_the_main_process_only_when_it_first_runs(photo):
    import sys

    sys.modules.pop("fixture_deferred", None)
    host = fixture_host("good", "deferred", "deferred_mismatched")
    assert set(host.detectors) == {"good", "deferred", "deferred_mismatched"}
    assert "fixture_deferred" not in sys.modules
    findings = by_name(analyze(photo, ["good", "deferred", "deferred_mismatched"], host=host, jobs=2))
    assert "fixture_deferred" in sys.modules
    assert findings["deferred"].status is Status.OK and findings["deferred"].details["prior"] == []
    assert findings["deferred_mismatched"].status is Status.ERROR
    assert "is not a Detector whose spec is the one registered" in findings["deferred_mismatched"].error
    assert findings["good"].status is Status.OK


def test_a_raising_detector_is_recorded_and_the_others_survive(photo):
    host = fixture_host("good", "raising")
    findings = by_name(analyze(photo, host=host, timeout=30))
    assert findings["good"].status is Status.OK
    assert findings["raising"].status is Status.ERROR
    assert "RuntimeError: boom in the detector" in findings["raising"].error
    assert "Traceback" in findings["raising"].details["traceback"]


def test_a_hanging_detector_is_stopped_at_its_time_limit(photo):
    host = fixture_host("good", "hanging")
    findings = by_name(analyze(photo, host=host, timeout=1.5))
    assert findings["hanging"].status is Status.ERROR
    assert "timed out after 1.5 s" in findings["hanging"].error
    assert findings["hanging"].elapsed_s < 10
    assert findings["good"].status is Status.OK


def test_inline_isolation_also_reports_the_time_limit(photo):
    host = fixture_host("hanging")
    finding = analyze(photo, host=host, timeout=0.5, isolation="inline").detectors[0]
    assert finding.status is Status.ERROR and "timed out" in finding.error


def test_garbage_and_out_of_range_results_are_refused(photo, validate):
    host = fixture_host("garbage", "out_of_range", "good")
    result = analyze(photo, host=host, timeout=30)
    findings = by_name(result)
    assert "expected a DetectorResult, got dict" in findings["garbage"].error
    assert "outside [0, 1]" in findings["out_of_range"].error
    assert findings["good"].status is Status.OK
    validate(result)


def test_a_crashing_detector_costs_only_itself(photo):
    findings = by_name(analyze(photo, host=fixture_host("crashing", "good"), timeout=30))
    assert "died" in findings["crashing"].error
    assert findings["good"].status is Status.OK


def test_a_detector_cannot_write_to_the_evidence(photo):
    finding = analyze(photo, host=fixture_host("mutating"), timeout=30, isolation="inline").detectors[0]
    assert finding.status is Status.ERROR
    assert "read-only" in finding.error


def test_broken_plugins_are_recorded_not_fatal(photo, validate):
    host = fixture_host("good", "bad_registration", "typo", "wrong_args", "not_a_detector", "two_names")
    host.load_entry_point(EntryPoint("broken", "broken_import_plugin", ENTRY_POINT_GROUP))
    host.load_entry_point(EntryPoint("missing", "no_such_module_anywhere:plugin", ENTRY_POINT_GROUP))
    records = host.records
    assert records["broken"].status == "error" and "needs a library" in records["broken"].error
    assert records["missing"].status == "error" and "ModuleNotFoundError" in records["missing"].error
    assert "cannot register" in records["bad_registration"].error
    assert "unknown hook(s) forensics_analyse" in records["typo"].error
    assert "invalid hooks" in records["wrong_args"].error
    assert "takes a forensics_core.Detector, not DetectorSpec" in records["not_a_detector"].error
    assert "already provided" in records["two_names"].error and records["two_names"].detectors == []
    assert records["good"].status == "loaded"
    result = analyze(photo, host=host, timeout=30)
    doc = validate(result)
    assert {p["name"]: p["status"] for p in doc["plugins"]}["broken"] == "error"
    assert by_name(result)["good"].status is Status.OK


def test_a_plugin_written_for_api_1_fails_to_load_saying_what_to_change():
    host = fixture_host("api_one", "api_one_specs", "good")
    old = host.records["api_one"]
    assert old.status == "error"
    assert "written for plugin API 1: forensics_analyze is now Detector.analyze" in old.error
    assert "forensics_register_detectors(register)" in old.error
    specs = host.records["api_one_specs"]
    assert specs.status == "error" and "register(detector)" in specs.error
    assert set(host.detectors) == {"good"}


def test_detector_name_clash_is_a_load_error():
    host = fixture_host("good")
    host.load_entry_point(EntryPoint("good_again", "fixture_plugins:good", ENTRY_POINT_GROUP))
    assert host.records["good_again"].status == "error"
    assert "already" in host.records["good_again"].error


def test_unknown_detector_is_an_error_finding(photo):
    finding = analyze(photo, ["nope"], host=fixture_host("good")).detectors[0]
    assert finding.status is Status.ERROR and "no loaded plugin provides detector 'nope'" in finding.error


def test_a_failing_fusion_plugin_does_not_spoil_another_policys_verdict(photo):
    host = fixture_host("good", "raising_fusion")
    alone = analyze(photo, host=fixture_host("good")).verdict
    verdict = analyze(photo, host=host).verdict
    assert verdict.policy == "bonferroni" and verdict.label is alone.label and "fusion broke" not in verdict.explanation
    unknown = analyze(photo, host=host, fusion="nobody_has_it").verdict
    assert unknown.label is VerdictLabel.INCONCLUSIVE
    assert unknown.explanation == ("No verdict by fusion policy 'nobody_has_it': plugin 'raising_fusion' failed: "
                                   "RuntimeError: fusion broke.")


def test_forensics_fuse_is_called_through_pluggy_and_its_first_result_decides(photo):
    import fixture_plugins

    fixture_plugins.FUSED.clear()
    late = analyze(photo, host=fixture_host("good", "early_fusion", "late_fusion"), fusion="first").verdict
    assert late.explanation == "Decided by late_fusion."
    assert fixture_plugins.FUSED == ["late_fusion"]
    fixture_plugins.FUSED.clear()
    first = analyze(photo, host=fixture_host("good", "early_fusion", "first_fusion", "late_fusion"),
                    fusion="first").verdict
    assert first.explanation == "Decided by first_fusion." and fixture_plugins.FUSED == ["first_fusion"]
    fixture_plugins.FUSED.clear()
    builtin = analyze(photo, host=fixture_host("good", "late_fusion", "raising_fusion")).verdict
    assert builtin.policy == "bonferroni" and fixture_plugins.FUSED == ["late_fusion"]


def test_extra_metadata_hook(photo):
    result = analyze(photo, host=fixture_host("metadata", "good"))
    assert result.evidence.extra_metadata["metadata"] == {"bytes": photo.stat().st_size}


def test_plugins_command_lists_status_and_errors(monkeypatch):
    result = CliRunner().invoke(cli, ["plugins", "--json"])
    assert result.exit_code == 0, result.output
    payload = json.loads(result.output)
    assert payload["entry_point_group"] == ENTRY_POINT_GROUP
    names = {p["name"]: p for p in payload["plugins"]}
    assert names["lens_distortion"]["status"] == "loaded"
    assert names["lens_distortion"]["hooks"] == ["forensics_register_commands", "forensics_register_detectors"]
    assert names["lens_distortion"]["detectors"] == ["lens_distortion"]
    table = CliRunner().invoke(cli, ["plugins"])
    assert table.exit_code == 0 and "lens_distortion" in table.output


def test_a_plugin_that_writes_to_the_evidence_file_is_caught_and_said_loudly(photo, tmp_path):
    from forensics_core.analysis import Options
    from forensics_core.output import Placement
    from forensics_core.pipeline import examine_photo

    copy = tmp_path / "copy.jpg"
    copy.write_bytes(Path(photo).read_bytes())
    done = examine_photo(copy, lambda ev, fi: Placement(tmp_path / "out"), fixture_host("file_writer"),
                         Options(timeout_s=30))
    note = done.findings.evidence.changed_during_analysis
    assert note and "changed during the analysis" in note and "wrote to it" in note
    assert json.loads(done.findings_path.read_text())["evidence"]["changed_during_analysis"] == note


def test_what_a_detector_prints_is_kept_in_its_finding_not_on_our_terminal(photo, capfd):
    finding = analyze(photo, host=fixture_host("chatty"), timeout=60).detectors[0]
    out, err = capfd.readouterr()
    assert "line 0" not in out and "a library complains" not in err
    assert finding.status is Status.OK and finding.output.startswith("line 0\nline 1\n")
    assert len(finding.output) < 4100 and "bytes in all)" in finding.output


def test_a_metadata_hook_that_hangs_is_stopped_at_the_time_limit(photo):
    findings = analyze(photo, host=fixture_host("metadata_hanging", "good"), timeout=3)
    assert "timed out after 3 s" in findings.evidence.extra_metadata["metadata_hanging"]["error"]
    assert findings.detectors[0].status is Status.OK


def test_detectors_run_at_once_give_the_findings_of_a_run_one_at_a_time(photo):
    names = ["reader", "hanging", "good", "raising", "crashing"]
    host = fixture_host(*names)

    def comparable(findings):
        return {d.name: (d.status, d.error, d.score, d.p_value, d.details.get("seen")) for d in findings.detectors}

    one = analyze(photo, names, host=host, timeout=2, jobs=1)
    started = time.monotonic()
    three = analyze(photo, names, host=host, timeout=2, jobs=3)
    # The hanging detector is stopped at its limit while the others run beside it.
    assert time.monotonic() - started < 6
    assert comparable(three) == comparable(one)
    assert [d.name for d in three.detectors] == names
    reader = by_name(three)["reader"]
    assert reader.details["seen"] == {"good": by_name(three)["good"].details["mean_luma"]}
    assert "timed out after 2 s" in by_name(three)["hanging"].error
    assert "died" in by_name(three)["crashing"].error


def test_options_are_resolved_once_for_a_run(photo):
    from forensics_core.analysis import Options, analyze_evidence
    from forensics_core.evidence import load_evidence

    host = fixture_host("good")
    options = Options(detector_params={"good": {"level": 3}}).resolve(host)
    assert options.resolved and options.detectors == ["good"] and options.detector_params == {"good": {"level": 3}}
    assert options.resolve(host) is options
    findings = analyze_evidence(load_evidence(photo), host, options)
    assert findings.parameters["detector_params"] == {"good": {"level": 3}}
    assert findings.detectors[0].details["level"] == 3
    with pytest.raises(ValueError, match="no parameter levle"):
        Options(detector_params={"good": {"levle": 1}}).resolve(host)
