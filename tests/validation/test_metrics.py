"""Error-rate statistics against textbook values and scipy."""

import numpy as np
import pytest
from scipy.stats import mannwhitneyu

from forensics_core.validation.metrics import auc_bootstrap_ci, f1, iou, mcc, rate, roc_auc, roc_curve, suspicion, tpr_at_fpr


def test_auc_is_the_mann_whitney_probability_with_ties_counted_half():
    rng = np.random.default_rng(0)
    pos = np.round(rng.normal(1.0, 1.0, 40), 1)
    neg = np.round(rng.normal(0.0, 1.0, 55), 1)
    u = mannwhitneyu(pos, neg).statistic
    assert roc_auc(pos, neg) == pytest.approx(u / (40 * 55))
    assert roc_auc(np.zeros(3), np.zeros(4)) == 0.5
    assert roc_auc(np.array([]), neg) is None


def test_bootstrap_interval_is_reproducible_and_brackets_the_auc():
    rng = np.random.default_rng(1)
    pos, neg = rng.normal(1, 1, 30), rng.normal(0, 1, 30)
    lo, hi = auc_bootstrap_ci(pos, neg)
    assert lo < roc_auc(pos, neg) < hi
    assert auc_bootstrap_ci(pos, neg) == (lo, hi)
    assert 0.1 < hi - lo < 0.4


def test_tpr_at_fpr_reads_the_roc_curve():
    pos = np.array([5.0, 4.0, 3.0, 0.5])
    neg = np.array([3.5, 1.0, 0.0, 0.0, 0.0])
    curve = roc_curve(pos, neg)
    assert curve[0] == (0.0, 0.0) and curve[-1] == (1.0, 1.0)
    assert tpr_at_fpr(curve, 0.0) == 0.5
    assert tpr_at_fpr(curve, 0.2) == 0.75


def test_rates_carry_exact_intervals():
    r = rate(0, 20)
    assert r.value == 0 and r.ci[0] == 0 and r.ci[1] == pytest.approx(0.1684, abs=1e-4)
    r = rate(5, 10)
    assert r.ci == pytest.approx((0.1871, 0.8129), abs=1e-4)
    assert rate(0, 0).value is None


def test_localisation_scores():
    truth = np.zeros((10, 10), bool)
    truth[:5] = True
    assert iou(truth, truth) == 1 and mcc(truth, truth) == pytest.approx(1)
    assert mcc(~truth, truth) == pytest.approx(-1)
    assert iou(np.zeros_like(truth), truth) == 0 and mcc(np.zeros_like(truth), truth) == 0
    half = truth.copy()
    half[:2] = False
    # Dice against Jaccard: F1 = 2 J / (1 + J).
    assert f1(half, truth) == pytest.approx(2 * iou(half, truth) / (1 + iou(half, truth)))
    assert f1(truth, truth) == 1 and f1(np.zeros_like(truth), np.zeros_like(truth)) == 0


def test_declined_results_rank_as_nothing_found():
    assert suspicion(1e-5, 0.9, decided=True) == pytest.approx(5)
    assert suspicion(None, 0.3, decided=True) == 0.3
    assert suspicion(1e-5, 0.9, decided=False) == 0.0
