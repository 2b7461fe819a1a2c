"""Likelihood-ratio calibrators: applying, fitting with lir, Cllr, ELUB bounds, the CLI; on score sets made here."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

from forensics_core.calibration import CalibrationError, Calibrator, Fusion, feature, load, verbal
from forensics_core.calibration.fit import CalibratorInput, calibrate, cases_from_rows, costs, scene
from forensics_core.calibration.model import CalibrationSet, supports
from forensics_core.cli import cli


def _record(tmp_path, n=40, seed=0, name="r.json"):
    """A validation record: 'strong' separates the propositions, 'noise' does not, 'shy' always declines."""
    rng = np.random.default_rng(seed)
    cases = []
    for i in range(n):
        hp = i % 2 == 1
        strong = float(10.0 ** -rng.uniform(3, 8)) if hp else float(rng.uniform(0.01, 1.0))
        cases.append({
            "name": f"set__photo{i // 2}_{'tamp' if hp else 'orig'}{i}", "spliced": hp, "error": None,
            "conditions": {"set": "made", "scene": f"s{i // 2}"},
            "detectors": {"strong": {"status": "ok", "p_value": strong},
                          "noise": {"status": "ok", "p_value": float(rng.uniform())},
                          "shy": {"status": "inconclusive", "p_value": None}},
        })
    path = tmp_path / name
    path.write_text(json.dumps({"dataset": {"name": "made", "source": "test", "content_sha256": "0" * 64,
                                            "n_cases": n, "n_spliced": n // 2, "n_authentic": n - n // 2},
                                "cases": cases}))
    return path


def test_a_calibrator_bounds_caps_and_gives_lr_1_when_the_detector_declines():
    cal = Calibrator("d", intercept=-0.5, slope=0.4, lower=-1.0, upper=2.0, n_hp=10, n_hd=10)
    assert cal.log10_lr(None) == 0.0
    assert cal.log10_lr(1.0) == pytest.approx(-0.5)
    assert cal.log10_lr(1e-3) == pytest.approx(-0.5 + 1.2)
    assert cal.log10_lr(1e-300) == 2.0
    assert feature(0.0) == feature(1e-300) == 30.0 and feature(None) is None


def test_fusion_counts_an_absent_or_uncalibrated_detector_as_lr_1():
    fusion = Fusion(intercept=-0.1, weights={"a": 0.5, "b": 1.0}, lower=-1.0, upper=1.5)
    assert fusion.log10_lr({"a": 1.0}) == pytest.approx(0.4)
    assert fusion.log10_lr({"a": 4.0, "b": 4.0}) == 1.5
    cs = CalibrationSet(data={}, tool={}, fusion=fusion,
                        calibrators={"a": Calibrator("a", 0.0, 1.0, -2.0, 2.0, 5, 5)})
    llrs = cs.detector_llrs({"a": 0.1, "plugin_x": 1e-9, "b": None})
    assert llrs["plugin_x"] is None and llrs["a"] == pytest.approx(1.0)
    assert cs.fused(llrs) == pytest.approx(-0.1 + 0.5)


def test_the_fusion_intercept_tempers_the_detectors_evidence_but_creates_none():
    """With no detector away from LR 1 the fused LR is 1, whatever the calibration data's make-up."""
    for intercept in (-0.6, 0.3):
        fusion = Fusion(intercept=intercept, weights={"a": 1.0, "b": 1.0}, lower=-2.0, upper=2.0)
        assert fusion.log10_lr({}) == 0.0 and fusion.log10_lr({"a": 0.0, "b": 0.0}) == 0.0
    fusion = Fusion(intercept=0.3, weights={"a": 1.0, "b": 1.0}, lower=-2.0, upper=2.0)
    assert fusion.log10_lr({"a": 0.1}) == pytest.approx(0.1)  # not 0.4: no more than the detectors found
    assert fusion.log10_lr({"a": -0.5}) == pytest.approx(-0.2)  # tempered
    assert fusion.log10_lr({"a": -0.5, "b": 0.2}) == pytest.approx(0.0)
    assert Fusion(intercept=-0.6, weights={"a": 1.0}, lower=-2.0, upper=2.0).log10_lr({"a": 0.4}) == 0.0


def test_cllr_against_values_computed_by_hand():
    assert costs(np.array([0.0, 0.0]), np.array([0, 1]))[0] == pytest.approx(1.0)
    # One LR of 10 for Hp and one of 1/10 for Hd: each costs log2(1 + 1/10).
    assert costs(np.array([1.0, -1.0]), np.array([1, 0]))[0] == pytest.approx(math.log2(1.1))
    # Misleading in both directions costs log2(1 + 10).
    assert costs(np.array([-1.0, 1.0]), np.array([1, 0]))[0] == pytest.approx(math.log2(11.0))


def test_fitting_is_deterministic_bounded_and_ranks_detectors(tmp_path):
    path = _record(tmp_path)
    first, second = calibrate([path]), calibrate([path])
    assert first.to_json() == second.to_json()
    strong, noise, shy = (first.calibrators[d] for d in ("strong", "noise", "shy"))
    assert strong.slope > 0 and strong.cllr < 0.5 and strong.cllr < noise.cllr
    assert shy.n_declined_hp == 20 and shy.n_declined_hd == 20 and shy.log10_lr(1e-9) == 0.0
    # ELUB: with 20 photos per side no LR may exceed what one more misleading photo would refute.
    assert 0.0 < strong.upper < math.log10(40) and -math.log10(40) < strong.lower <= 0.0
    assert all(strong.lower <= strong.log10_lr(p) <= strong.upper for p in (1.0, 1e-3, 1e-30, 0.0))
    assert first.fusion.cllr <= noise.cllr
    assert first.data["n_hp"] == 20 and first.data["n_scenes"] == 20


def test_scene_keeps_variants_of_one_photo_together():
    assert scene("micc_f220__DSC_1535tamp27", {"set": "micc"}) == scene("micc_f220__DSC_1535_scale", {"set": "micc"})
    assert scene("imd_pairs__forged_I02_dm545yj_0", {"set": "imd"}) == scene("imd_pairs__original_I02_6vzqfn",
                                                                               {"set": "imd"})
    assert scene("x__a", {"scene": "s9"}) == "s9"


def test_one_file_held_under_two_names_is_one_scene_with_the_edits_of_both():
    def row(name, digest, spliced):
        return {"name": name, "sha256": digest, "spliced": spliced, "conditions": {"set": "imd"},
                "detectors": {"d": {"status": "ok", "p_value": 0.5, "score": None}}}

    rows = [row("imd_pairs__original_I24_4qhnk9", "aa", False), row("imd_pairs__forged_I24_d4t4tzx_0", "b1", True),
            row("imd_pairs__original_I34_4qhnk9", "aa", False), row("imd_pairs__forged_I34_d4t7pgj_0", "b2", True),
            row("imd_pairs__original_I02_6vzqfn", "cc", False), row("bad", "aa", False) | {"error": "unreadable"}]
    scenes = [c.scene for c in cases_from_rows(rows)]
    assert len(scenes) == 5 and len(set(scenes[:4])) == 1 and scenes[4] != scenes[0]


def test_cli_writes_a_loadable_file_and_prints_the_costs(tmp_path):
    out = tmp_path / "cal.json"
    result = CliRunner().invoke(cli, ["calibrate", str(_record(tmp_path)), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "Cllr" in result.output and "fused" in result.output
    loaded = load(out)
    assert set(loaded.calibrators) == {"strong", "noise", "shy"} and loaded.fusion is not None


@pytest.mark.parametrize("content, words", [
    (b"{", "not a validation record (not JSON"),
    (b"\xff\xfe", "not a validation record (not UTF-8 text)"),
    (b'{"format": 1}', "not a validation record of `forensics validate` (no 'dataset' field)"),
    (b"[]", "not a validation record of `forensics validate` (fields of the wrong kind)"),
])
def test_cli_bad_record_is_one_line(tmp_path, content, words):
    bad = tmp_path / "bad.json"
    bad.write_bytes(content)
    result = CliRunner().invoke(cli, ["calibrate", str(bad), "--out", str(tmp_path / "c.json")])
    assert result.exit_code == 2 and len(result.output.strip().splitlines()) == 1
    assert result.output.startswith(f"forensics: error: {bad}: {words}")
    with pytest.raises(CalibrationError):
        load(bad)


def test_verbal_equivalents():
    assert verbal(0.1).startswith("no support")
    assert verbal(1.5) == "moderate support for Hp (manipulation)"
    assert verbal(-2.5) == "moderately strong support for Hd (as the camera produced it)"
    assert verbal(7.0).startswith("extremely strong")


def test_the_side_an_lr_supports_is_the_side_its_words_name():
    for log10_lr in np.linspace(-1.0, 1.0, 401).tolist() + [math.log10(2.0), -math.log10(2.0)]:
        side = supports(log10_lr)
        words = verbal(log10_lr)
        assert side == (1 if "for Hp" in words else -1 if "for Hd" in words else 0), (log10_lr, words)
    assert supports(None) == 0 and supports(math.log10(2.0)) == 1 and supports(-0.3) == 0


def _analyze(*args):
    return subprocess.run([sys.executable, "-m", "forensics_core", "analyze", *map(str, args)], capture_output=True,
                          text=True, timeout=300)


def test_findings_carry_each_detectors_and_the_fused_lr_with_their_calibration(photo, tmp_path, validate):
    out = _analyze(photo, "--out", tmp_path / "shipped", "--format", "json", "--detectors", "jpeg_grid,metadata")
    assert out.returncode == 0, out.stderr
    findings = json.loads((tmp_path / "shipped" / "left01" / "findings.json").read_text())
    validate(findings)
    lr = findings["verdict"]["likelihood_ratio"]
    assert lr["calibration"]["records"][0]["name"] == "real" and lr["hp"].startswith("after capture")
    assert findings["verdict"]["log10_lr"] == lr["log10_lr"] is not None
    assert all(d["log10_lr"] is not None for d in findings["detectors"])
    # A calibration file of the examiner's own: a detector it does not cover is shown but stays out of the LR.
    record = _record(tmp_path)
    text = record.read_text().replace('"strong"', '"jpeg_grid"')
    record.write_text(text)
    own = tmp_path / "own.json"
    assert CliRunner().invoke(cli, ["calibrate", str(record), "--out", str(own)]).exit_code == 0
    out = _analyze(photo, "--out", tmp_path / "own", "--format", "json", "--detectors", "jpeg_grid,metadata",
                   "--calibration", own)
    assert out.returncode == 0, out.stderr
    findings = json.loads((tmp_path / "own" / "left01" / "findings.json").read_text())
    validate(findings)
    lr = findings["verdict"]["likelihood_ratio"]
    assert lr["calibration"]["records"][0]["name"] == "made" and "metadata" not in lr["contributed"]
    assert findings["parameters"]["calibration"] == str(own.resolve())
    assert {d["name"]: d["log10_lr"] for d in findings["detectors"]}["metadata"] is None


def test_a_bad_calibration_file_is_a_usage_error_in_one_line(photo, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "other"}')
    out = _analyze(photo, "--out", tmp_path / "o", "--format", "json", "--calibration", bad)
    assert out.returncode == 2 and "calibration" in out.stderr and "Traceback" not in out.stderr


@pytest.mark.parametrize("log10_lr, label", [(2.5, "inconsistent"), (-2.0, "consistent"), (1.9, "inconclusive"),
                                             (None, "inconclusive")])
def test_the_likelihood_ratio_policy_labels_by_fixed_thresholds(log10_lr, label):
    from forensics_core.evaluation import decide_by_lr
    from forensics_core.findings import DetectorFinding, LikelihoodRatio, Status
    from forensics_core.fusion import likelihood_ratio

    finding = DetectorFinding(name="a", version="1", plugin="p", status=Status.OK, summary="s", score=None,
                              p_value=1e-6, nfa=None, details={}, parameters={}, elapsed_s=0.1)
    verdict = likelihood_ratio([finding])
    assert verdict.label.value == "inconclusive" and "1/100" in verdict.method
    verdict.likelihood_ratio = LikelihoodRatio(hp="h", hd="d", log10_lr=log10_lr, contributed=["a"],
                                               verbal=verbal(log10_lr) if log10_lr is not None else "")
    decide_by_lr(verdict)
    assert verdict.label.value == label
    assert verdict.drivers == ([] if label == "inconclusive" else ["a"])


def test_analyze_with_the_likelihood_ratio_policy(photo, tmp_path, validate):
    out = _analyze(photo, "--out", tmp_path / "o", "--format", "json", "--detectors", "jpeg_grid",
                   "--fusion", "likelihood_ratio")
    assert out.returncode == 0, out.stderr
    findings = json.loads((tmp_path / "o" / "left01" / "findings.json").read_text())
    validate(findings)
    verdict = findings["verdict"]
    assert verdict["policy"] == "likelihood_ratio" and "fused likelihood ratio" in verdict["explanation"]
    # The shipped calibrators cannot support an LR of 100 either way on their data (ELUB), so: inconclusive.
    assert verdict["label"] == "inconclusive"


def test_relevance_says_whether_the_photo_lies_within_the_calibration_data(photo):
    from forensics_core import load_evidence
    from forensics_core.evaluation import evaluate
    from forensics_core.findings import Verdict, VerdictLabel

    info = load_evidence(photo).info
    mp = info.width * info.height / 1e6

    def relevance(**data):
        cs = CalibrationSet(data={"n_hp": 3, "n_hd": 4, "sets": ["made"], **data}, tool={}, calibrators={},
                            fusion=Fusion(0.0, {}, -1.0, 1.0))
        verdict = Verdict(VerdictLabel.INCONCLUSIVE, None, "x", "bonferroni")
        evaluate([], verdict, info, cs)
        return verdict.likelihood_ratio.relevance

    assert "lies within" in relevance(formats=["JPEG"], megapixels=[mp / 2, mp * 2])
    outside = relevance(formats=["PNG"], megapixels=[mp * 2, mp * 4])
    assert "outside them" in outside and "format (JPEG)" in outside and "size" in outside
    assert "not recorded" in relevance()


def test_a_detector_that_states_no_p_value_is_calibrated_on_its_score(tmp_path):
    """A measured statistic without a test (copy_move's grain peak) gets an LR from its score."""
    path = _record(tmp_path)
    record = json.loads(path.read_text())
    rng = np.random.default_rng(3)
    for case in record["cases"]:
        score = float(rng.uniform(0.4, 0.9)) if case["spliced"] else float(rng.uniform(0.0, 0.3))
        case["detectors"]["measured"] = {"status": "ok", "p_value": None, "score": score}
    case = record["cases"][0]
    case["detectors"]["measured"] = {"status": "inconclusive", "p_value": None, "score": None}
    path.write_text(json.dumps(record))
    assert calibrate([path]).calibrators["measured"].n_declined_hd == 20  # on p-values it never ran
    cs = calibrate([path], features={"measured": CalibratorInput("score")})
    measured = cs.calibrators["measured"]
    assert measured.feature == "score" and cs.calibrators["strong"].feature == "p"
    assert measured.slope > 0 and measured.cllr < cs.calibrators["noise"].cllr and measured.cllr_min < 0.1
    assert measured.n_declined_hd == 1
    assert measured.log10_lr(None, None) == 0.0
    assert measured.log10_lr(None, 0.9) > 0.0 > measured.log10_lr(None, 0.05)
    llrs = cs.detector_llrs({"measured": None, "strong": 1e-6}, {"measured": 0.8})
    assert llrs["measured"] == pytest.approx(measured.log10_lr(None, 0.8))
    reloaded = load_json(cs.to_json(), tmp_path)
    assert reloaded.calibrators["measured"].feature == "score"


def load_json(text, tmp_path):
    path = tmp_path / "cal.json"
    path.write_text(text)
    return load(path)


def test_a_score_detector_is_judged_at_its_calibrated_lr_not_at_score_above_0():
    from forensics_core import Status
    from forensics_core.calibration.fit import supports_hp
    from forensics_core.validation.record import compute_methods
    from forensics_core.validation.runner import CaseResult, DetectorOutcome

    rng = np.random.default_rng(4)
    results = []
    # 200 photos: with 60, the ELUB bounds (they grow with the sample) keep half the separated ones under LR 2.
    for i in range(200):
        hp = i % 2 == 1
        score = float(rng.uniform(0.5, 0.9) if hp else rng.uniform(0.0, 0.4))
        results.append(CaseResult(f"photo{i}", hp, {"set": "made", "scene": f"s{i}"}, "0" * 64, None, None,
                                  {"measured": DetectorOutcome(Status.OK, None, score, None, 0.0)}))
    rows = [{"name": r.name, "spliced": r.spliced, "error": None, "conditions": r.conditions,
             "detectors": {"measured": {"status": "ok", "p_value": None, "score": r.detectors["measured"].score}}}
            for r in results]
    flags = supports_hp(rows, {"measured": CalibratorInput("score")})
    (plain,) = [m for m in compute_methods(results, {"measured": "1"}, 0.01) if m.name == "measured"]
    (by_lr,) = [m for m in compute_methods(results, {"measured": "1"}, 0.01, flags) if m.name == "measured"]
    plain, by_lr = plain.operating_point, by_lr.operating_point
    assert plain.rule == "score above 0" and by_lr.rule.startswith("calibrated LR of 2 or more")
    # Measured: every authentic photo has a score above 0; none has an LR of 2 or more, 85 of 100 manipulated do.
    assert plain.fpr.k >= 95 and by_lr.fpr.k <= 3 and by_lr.tpr.k >= 75


def test_the_four_parameter_logistic_is_the_line_without_floor_and_ceiling_and_bounded_with_them():
    from forensics_core.calibration.model import four_parameter_log10_lr

    assert four_parameter_log10_lr(0.7, -0.5, 2.0, 0.0, 0.0) == pytest.approx(0.9)
    c, d = 0.05, 0.04
    floor, ceiling = math.log10(c / (1 - c)), math.log10((c + (1 - c) / (1 + d)) / ((1 - c) * d / (1 + d)))
    xs = np.linspace(-20.0, 20.0, 81)
    llrs = [four_parameter_log10_lr(x, -1.0, 3.0, c, d) for x in xs]
    assert np.all(np.diff(llrs) >= 0) and llrs[40] - llrs[39] > 0.1
    assert llrs[0] == pytest.approx(floor, abs=1e-6) and llrs[-1] == pytest.approx(ceiling, abs=1e-6)


def _mixed_score_record(tmp_path, n=400, seed=5):
    """Scores of a detector of one kind of manipulation: a quarter of Hp are manipulations it cannot see (scored as
    originals), and 4 % of Hd are scenes that mimic its trace (scored as manipulations)."""
    path = _record(tmp_path, n=n, seed=seed)
    record = json.loads(path.read_text())
    rng = np.random.default_rng(seed)
    for case in record["cases"]:
        mimic = rng.uniform() < (0.75 if case["spliced"] else 0.04)
        score = float(rng.uniform(0.3, 0.9) if mimic else rng.uniform(0.0, 0.2))
        case["detectors"]["measured"] = {"status": "ok", "p_value": None, "score": score}
    path.write_text(json.dumps(record))
    return path


def test_a_score_with_a_floor_and_a_ceiling_gets_the_four_parameter_logistic(tmp_path):
    """A line through such scores would keep rising past the scenes that mimic the trace; the four parameters stop
    the LR where the data do, and the better fit shows in the cross-validated Cllr."""
    path = _mixed_score_record(tmp_path)
    from forensics_core.calibration.fit import _logit_line, cases_from_rows, cross_validated

    measured = calibrate([path], features={"measured": CalibratorInput("score")}).calibrators["measured"]
    assert 0.1 < measured.floor < 0.4 and 0.0 < measured.ceiling < 0.25
    # Each cluster's LR is that of the mixture, 0.75 / 0.04 above and 0.25 / 0.96 below (up to the sample's 8
    # mimicking originals), where a line would rise and fall without end.
    assert 0.7 < measured.log10_lr(None, 0.9) < math.log10(0.75 / 0.04) + 0.3
    assert math.log10(0.25 / 0.96) - 0.3 < measured.log10_lr(None, 0.0) < math.log10(0.25 / 0.96) + 0.3
    rows = json.loads(path.read_text())["cases"]
    y = np.array([c["spliced"] for c in rows])
    four, _ = cross_validated(["measured"], cases_from_rows(rows), {"measured": CalibratorInput("score")})
    assert costs(four["measured"], y)[0] < 0.75

    clean = calibrate([path], features={"noise": CalibratorInput("score")}).calibrators["noise"]
    assert clean.floor == clean.ceiling == 0.0  # no score: not fitted; and a p-value calibrator stays a line
    assert calibrate([path]).calibrators["strong"].floor == 0.0
    assert _logit_line(np.array([0.0, 1.0]), np.array([0, 1]))[1] > 0


def test_a_one_sided_calibrator_never_supports_hd(tmp_path):
    """A detector of one kind of manipulation that finds none says nothing about the others Hp covers."""
    path = _mixed_score_record(tmp_path)
    two = calibrate([path], features={"measured": CalibratorInput("score")}).calibrators["measured"]
    one = calibrate([path], features={"measured": CalibratorInput("score", one_sided=True)}).calibrators["measured"]
    assert two.lower < -0.3 and two.log10_lr(None, 0.05) < -0.3
    assert one.lower == 0.0 and one.log10_lr(None, 0.05) == 0.0
    assert one.log10_lr(None, 0.8) == pytest.approx(two.log10_lr(None, 0.8))


def test_copy_move_finding_no_copy_is_weighed_as_its_lowest_score():
    """copy_move scores a searched photo without a candidate 0 and is calibrated two-sided: finding no copy is
    rarer under Hp than under Hd on the calibration data, and its shipped LR says so, within the ELUB bounds."""
    from forensics_core.calibration import load_shipped
    from forensics_core.calibration.fit import calibrator_inputs
    from forensics_core.plugins import PluginHost

    inputs = calibrator_inputs(PluginHost.from_entry_points())
    assert inputs["copy_move"] == CalibratorInput("score")
    assert inputs["dq"] == CalibratorInput("score") and "jpeg_grid" not in inputs
    shipped = load_shipped().calibrators["copy_move"]
    assert shipped.lower < 0.0 and shipped.floor > 0.0
    assert shipped.lower <= shipped.log10_lr(None, 0.0) < 0.0
    assert shipped.log10_lr(None, None) == 0.0  # a decline (inconclusive) still counts for neither side


def _with_set_aucs(path, aucs, seed=None):
    """The record at ``path`` with per-set AUCs in its methods (as `forensics validate` writes) and a seed."""
    record = json.loads(path.read_text())
    record["dataset"]["seed"] = seed
    record["methods"] = [{"name": n, "by_condition": [{"key": "set", "value": "made", "auc": a}]}
                         for n, a in aucs.items()]
    path.write_text(json.dumps(record))
    return path


def test_only_detectors_informative_on_found_photos_are_fused(tmp_path):
    """A generated record teaches calibrators but earns no detector a weight that found photos do not give."""
    found = _with_set_aucs(_record(tmp_path, name="found.json"), {"strong": 0.9, "noise": 0.52, "shy": 0.5})
    made = _with_set_aucs(_record(tmp_path, seed=1, name="made.json"), {"strong": 0.95, "noise": 0.99}, seed=7)
    result = calibrate([found, made])
    assert result.data["fused"] == ["strong"]
    assert set(result.fusion.weights) == {"strong"}
    assert result.data["experimental"] == {"noise": 0.52, "shy": 0.5}
    assert result.data["records"][1]["seed"] == 7
    assert set(result.data["costs"]) == {"record made", "set made"}
    assert result.data["costs"]["set made"]["fused"]["n_hp"] == 40
    # Every detector still gets its calibrator, shown with its own LR in a report.
    assert set(result.calibrators) == {"strong", "noise", "shy"}


def test_without_found_aucs_every_detector_is_fused(tmp_path):
    made = _with_set_aucs(_record(tmp_path), {"strong": 0.95, "noise": 0.5}, seed=3)
    assert calibrate([made]).data["experimental"] == {}
