"""Dependence between detectors' p-values on authentic photos."""

import numpy as np

from forensics_core.validation.dependence import MIN_COMMON, authentic_dependence, pair_dependence


def _row(spliced, **p):
    return {"spliced": spliced, "error": None,
            "detectors": {n: {"status": "ok" if v is not None else "inconclusive", "p_value": v} for n, v in p.items()}}


def test_monotone_pair_is_dependent_and_independent_pair_is_not():
    rng = np.random.default_rng(1)
    a = rng.uniform(size=200)
    rows = [{"a": x, "b": x ** 2, "c": y} for x, y in zip(a, rng.uniform(size=200))]
    pairs = {(d.a, d.b): d for d in pair_dependence(rows)}
    assert pairs[("a", "b")].tau == 1.0 and pairs[("a", "b")].rejected
    assert abs(pairs[("a", "c")].tau) < 0.15 and not pairs[("a", "c")].rejected


def test_too_few_common_photos_or_a_constant_p_is_not_measured():
    rows = [{"a": 0.1 * i, "b": 0.5} for i in range(1, 30)] + [{"c": 0.3}] * (MIN_COMMON - 1)
    for d in pair_dependence(rows):
        assert d.tau is None and d.p_value is None and not d.rejected


def test_only_authentic_photos_and_stated_tests_count():
    cases = [_row(False, a=p, b=p) for p in np.linspace(0.05, 1, 12)]
    cases += [_row(True, a=0.001, b=0.9)] * 50 + [_row(False, a=0.5, b=None)] * 50
    (d,) = authentic_dependence(cases)
    assert d.n == 12 and d.tau == 1.0
