"""The null check on authentic photos: the empirical CDF, its validity test, convictions at the verdict's rule."""

import numpy as np
import pytest

from forensics_core.validation.null_check import (
    VERDICT,
    authentic_p_values,
    convictions,
    ecdf,
    null_check,
    null_checks,
    pointwise_limit,
    superuniformity_p,
)

BONFERRONI = {"policy": "bonferroni", "alpha": 0.01}


def test_ecdf_counts_ties_and_steps_at_each_distinct_value():
    x, y = ecdf(np.array([0.5, 0.1, 1.0, 0.1]))
    assert x.tolist() == [0.1, 0.5, 1.0] and y.tolist() == [0.5, 0.75, 1.0]


def test_valid_p_values_pass_and_too_many_small_ones_fail():
    n = 200
    uniform = (np.arange(n) + 0.5) / n
    assert superuniformity_p(uniform) > 0.5
    # Conservative tests (all p = 1) are valid too.
    assert superuniformity_p(np.ones(n)) == 1.0
    # A quarter of the photos at p = 1e-30: far more than a share 1e-30 of them.
    convicting = np.r_[np.full(n // 4, 1e-30), uniform[n // 4:]]
    assert superuniformity_p(convicting) < 1e-6
    assert superuniformity_p(np.array([])) is None


def test_the_uniform_test_is_not_rejected_more_often_than_its_level():
    rng = np.random.default_rng(7)
    rejected = [superuniformity_p(rng.uniform(size=50)) < 0.05 for _ in range(400)]
    assert np.mean(rejected) <= 0.05


def test_pointwise_limit_lies_above_the_diagonal():
    x = np.array([0.01, 0.1, 0.5])
    assert np.all(pointwise_limit(x, 100) >= x)


def row(name, spliced, detectors, verdict="consistent", verdict_p=1.0, where="s1"):
    return {"name": name, "spliced": spliced, "conditions": {"set": where}, "error": None, "verdict": verdict,
            "verdict_p": verdict_p, "detectors": detectors}


def ok(p):
    return {"status": "ok", "p_value": p, "score": 1 - p}


NO = {"status": "inconclusive"}


@pytest.fixture
def cases():
    return [
        # 0.004 alone is below 0.01; with a second test on the photo, 2 x 0.004 is still below.
        row("a1", False, {"g": ok(0.004), "l": ok(0.5), "m": {"status": "ok", "score": 0.2}}, "inconsistent", 0.008),
        # 0.004 with three tests: 0.012, not convicted; but it counts in the curve.
        row("a2", False, {"g": ok(0.004), "l": ok(0.9), "c": ok(0.7)}, "consistent", 0.012),
        # A detector that declined contributes no p-value and convicts nothing.
        row("a3", False, {"g": NO, "l": ok(1e-9)}, "inconsistent", 1e-9, where="s2"),
        row("a4", False, {"g": NO, "l": NO}, "inconclusive", None, where="s2"),
        row("s1", True, {"g": ok(1e-6), "l": ok(0.3)}, "inconsistent", 2e-6),
        {**row("bad", False, {}), "error": "could not be read"},
    ]


def test_detector_null_check_at_the_bonferroni_rule(cases):
    g = null_check(cases, "g", BONFERRONI)
    assert (g.n_authentic, g.n_tested, g.smallest_p) == (4, 2, 0.004)
    assert (g.below["0.01"].k, g.below["0.01"].n, g.below["0.001"].k) == (2, 2, 0)
    assert (g.convicted.k, g.convicted.n, g.convicted_cases) == (1, 4, ["a1"])
    assert g.convicted.ci[0] > 0 and g.convicted.ci[1] < 1
    assert "Bonferroni" in g.rule
    by_set = {s.set: s for s in g.by_set}
    assert by_set["s1"].auc == 1.0 and by_set["s1"].n_spliced == 1 and by_set["s1"].auc_ci == (1.0, 1.0)
    assert by_set["s2"].auc is None and by_set["s2"].declined.k == 2
    assert authentic_p_values(cases, "g").tolist() == [0.004, 0.004]


def test_without_bonferroni_a_detector_is_judged_at_the_level_itself(cases):
    g = null_check(cases, "g", {"policy": "fisher", "alpha": 0.01})
    assert g.convicted_cases == ["a1", "a2"] and "no adjustment" in g.rule


def test_verdict_and_the_list_of_convicted_authentic_photos(cases):
    checks = null_checks(cases, BONFERRONI)
    assert [c.name for c in checks] == ["c", "g", "l", "m", VERDICT]
    verdict = checks[-1]
    assert verdict.convicted_cases == ["a1", "a3"] and verdict.n_tested == 3
    m = next(c for c in checks if c.name == "m")
    assert m.n_tested == 0 and m.convicted.k == 0 and m.superuniformity_p is None
    rows = [(c.case, c.set, c.detector, c.p, c.verdict) for c in convictions(cases, checks)]
    assert rows == [("a1", "s1", "g", 0.004, "inconsistent"), ("a3", "s2", "l", 1e-9, "inconsistent")]


def test_a_photo_the_verdict_alone_convicts_is_listed_under_the_verdict():
    fisher = {"policy": "fisher", "alpha": 0.01}
    cases = [row("f", False, {"g": ok(0.02), "l": ok(0.03)}, "inconsistent", 0.004)]
    rows = convictions(cases, null_checks(cases, fisher))
    assert [(c.detector, c.p) for c in rows] == [(VERDICT, 0.004)]
