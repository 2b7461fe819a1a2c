"""Binomial tails (exact and the Chernoff fallback) and intervals."""

import numpy as np
from scipy import stats

from forensics_plugins.cfa.significance import clopper_pearson, log10_binom_tail, log10_chernoff


def test_tail_matches_scipy_where_representable():
    k = np.array([0, 1, 5, 10, 20, 60, 95])
    n = np.array([10, 10, 10, 30, 40, 100, 100])
    for p in (0.25, 0.5):
        ours = log10_binom_tail(k, n, p)
        ref = np.log10(stats.binom.sf(k - 1, n, p))
        assert np.allclose(ours, ref, atol=1e-9)


def test_underflow_falls_back_to_a_conservative_bound():
    k, n = np.array([2000]), np.array([2000])
    value = log10_binom_tail(k, n, 0.5)[0]
    assert np.isfinite(value)
    assert value >= 2000 * np.log10(0.5) - 1e-9  # the bound is never below the exact tail
    assert np.all(log10_chernoff(np.array([30, 60]), np.array([100, 100]), 0.5)
                  >= np.log10(stats.binom.sf(np.array([29, 59]), 100, 0.5)))


def test_clopper_pearson_covers_the_rate():
    lo, hi = clopper_pearson(40, 50)
    assert lo < 0.8 < hi
    assert clopper_pearson(0, 0) == (None, None)
    assert clopper_pearson(10, 10)[1] == 1.0


def test_tail_takes_a_probability_per_count():
    k = np.array([5, 20, 60])
    n = np.array([10, 40, 100])
    p = np.array([0.5, 0.6, 0.75])
    assert np.allclose(log10_binom_tail(k, n, p), np.log10(stats.binom.sf(k - 1, n, p)), atol=1e-9)
    assert np.all(log10_chernoff(k, n, p) >= log10_binom_tail(k, n, p) - 1e-12)
