"""The fusion policies, the roles they give each detector, and detectors that read others' findings."""

import pytest
from plugin_hosts import fixture_host
from scipy.stats import combine_pvalues

from forensics_core import Status, VerdictLabel, analyze
from forensics_core.calibration import verbal
from forensics_core.findings import DetectorFinding, LikelihoodRatio, Role
from forensics_core.fusion import ALPHA, bonferroni, fisher, fisher_p
from forensics_core.report import wording


def finding(name, status=Status.OK, p=None, nfa=None):
    return DetectorFinding(name=name, version="1", plugin="test", status=status, summary="s", score=None,
                           p_value=p, nfa=nfa, details={}, parameters={}, elapsed_s=0.0)


def roles(verdict):
    return {c.detector: c.role for c in verdict.contributions}


def test_bonferroni_rejects_on_the_adjusted_p_and_names_the_drivers():
    findings = [finding("lens", p=0.001), finding("grid", nfa=0.5), finding("cfa", p=0.3),
                finding("meta"), finding("broken", Status.ERROR), finding("flat", Status.INCONCLUSIVE)]
    v = bonferroni(findings)
    assert v.label is VerdictLabel.INCONSISTENT
    assert v.drivers == ["lens"]
    assert v.p_value == pytest.approx(0.003) and v.alpha == ALPHA
    assert roles(v) == {"lens": Role.DROVE, "grid": Role.COUNTED, "cfa": Role.COUNTED,
                        "meta": Role.ADVISORY, "broken": Role.NOT_COUNTED, "flat": Role.NOT_COUNTED}
    assert "meta (no p-value)" in v.explanation and "broken (error)" in v.explanation


def test_bonferroni_needs_each_test_below_alpha_over_m():
    v = bonferroni([finding("a", p=0.004), finding("b", p=0.004), finding("c", p=0.004)])
    assert v.label is VerdictLabel.CONSISTENT
    assert v.p_value == pytest.approx(0.012)
    # "Consistent" rests on every test that ran failing to reject, so all of them drove it.
    assert set(roles(v).values()) == {Role.DROVE} and v.drivers == ["a", "b", "c"]


def test_fisher_pools_weak_independent_traces_that_bonferroni_does_not():
    findings = [finding("a", p=0.004), finding("b", p=0.004), finding("c", p=0.004)]
    v = fisher(findings)
    assert v.label is VerdictLabel.INCONSISTENT
    assert v.p_value == pytest.approx(combine_pvalues([0.004] * 3, method="fisher").pvalue)
    assert v.drivers and set(v.drivers) <= {"a", "b", "c"}
    assert fisher_p([0.0]) == pytest.approx(0.0, abs=1e-200)


def test_fisher_drivers_are_the_fewest_tests_that_reject_alone():
    v = fisher([finding("strong", p=1e-6), finding("weak", p=0.5), finding("null", p=0.9)])
    assert v.label is VerdictLabel.INCONSISTENT and v.drivers == ["strong"]
    assert roles(v) == {"strong": Role.DROVE, "weak": Role.COUNTED, "null": Role.COUNTED}
    assert fisher([finding("a", p=0.3), finding("b", p=0.6)]).drivers == ["a", "b"]


@pytest.mark.parametrize("rule", [bonferroni, fisher])
def test_no_test_is_inconclusive_never_consistent(rule):
    v = rule([finding("meta"), finding("lens", Status.INCONCLUSIVE), finding("x", Status.ERROR)])
    assert v.label is VerdictLabel.INCONCLUSIVE and v.p_value is None and v.drivers == []
    assert wording.strength(v).words == "not evaluated" and not wording.strength(v).graded


def test_strength_is_the_likelihood_ratio_never_a_graded_p_value():
    v = bonferroni([finding("a", p=1e-9)])
    assert wording.strength(v).words == "not evaluated"
    v.likelihood_ratio = LikelihoodRatio(hp="h", hd="d", log10_lr=1.5, verbal=verbal(1.5))
    assert wording.strength(v).words == "moderate support for Hp (manipulation)" and wording.strength(v).graded
    assert wording.lr_words(1.0) == "about 10 times more probable"
    assert wording.lr_words(-2.0) == "about 100 times less probable"
    assert all("p-value" not in step.condition for step in wording.scale())


def test_the_statement_names_the_fused_bounds_and_a_detector_calibrated_on_its_own_data_beyond_them():
    v = bonferroni([finding("a", p=0.5)])
    v.likelihood_ratio = LikelihoodRatio(hp="h", hd="d", log10_lr=2.0, verbal=verbal(2.0),
                                         calibration={"elub_fused": [-0.5, 1.5]})
    assert wording.statement(v).bounds == "Its calibration data support likelihood ratios from 1/3.16 to 31.6 (ELUB bounds)."
    v.likelihood_ratio.calibration["own_calibration"] = {"prnu": {"source": "reference photos"}}
    bounds = wording.statement(v).bounds
    assert bounds.startswith("Its calibration data support likelihood ratios from 1/3.16 to 31.6 (ELUB bounds) for the "
                             "detectors fused; the likelihood ratio of prnu, calibrated on its own data")
    assert bounds.endswith("so the statement may lie beyond that range.")


def test_the_fusion_policy_is_chosen_by_name(photo):
    findings = analyze(photo, host=fixture_host("good"), fusion="fisher", timeout=60)
    assert findings.verdict.policy == "fisher"
    assert findings.verdict.method.startswith("Fisher")


def test_a_detector_reads_the_findings_it_uses_which_run_first(photo, validate):
    findings = analyze(photo, ["reader", "good"], host=fixture_host("good", "reader"), timeout=60)
    validate(findings)
    assert [d.name for d in findings.detectors] == ["reader", "good"]
    reader = findings.detectors[0]
    assert reader.details["seen"] == {"good": findings.detectors[1].details["mean_luma"]}
    assert roles(findings.verdict)["reader"] is Role.ADVISORY


def test_a_detector_still_runs_when_what_it_uses_was_not_selected(photo):
    findings = analyze(photo, ["reader"], host=fixture_host("good", "reader"), timeout=60)
    assert findings.detectors[0].status is Status.OK
    assert findings.detectors[0].details["seen"] == {}
