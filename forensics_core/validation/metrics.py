"""Error-rate statistics of a detector over photos of known origin.

Every detector is reduced to one *suspicion* per photo, higher meaning more
support for manipulation: ``-log10 p`` where it states a p-value (or an NFA,
taken as ``min(1, NFA)``), else its score; a detector that declined
(inconclusive) or failed gets 0, the value of "nothing found", so that the
curves describe what an examiner would have concluded. How often it declined
is reported beside them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

BOOTSTRAP_SAMPLES = 2000
BOOTSTRAP_SEED = 20261121
FPR_TARGETS = (0.01, 0.05)


def roc_auc(pos: np.ndarray, neg: np.ndarray) -> float | None:
    """Area under the ROC curve: P(suspicion of a spliced photo > that of an authentic one), ties counted half.

    Parameters
    ----------
    pos, neg : ndarray, shape (n_pos,), (n_neg,)
        Suspicions of spliced and authentic photos.

    Returns
    -------
    float or None
        None when either class is empty.
    """
    if len(pos) == 0 or len(neg) == 0:
        return None
    from scipy.stats import rankdata
    ranks = rankdata(np.concatenate([pos, neg]))
    u = ranks[: len(pos)].sum() - len(pos) * (len(pos) + 1) / 2.0
    return float(u / (len(pos) * len(neg)))


def auc_bootstrap_ci(pos: np.ndarray, neg: np.ndarray, level: float = 0.95) -> tuple[float, float] | None:
    """Percentile bootstrap interval of :func:`roc_auc`, resampling each class on its own.

    Uses :data:`BOOTSTRAP_SAMPLES` resamples from a fixed seed, so the interval
    is reproducible.
    """
    if len(pos) == 0 or len(neg) == 0:
        return None
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    p = pos[rng.integers(len(pos), size=(BOOTSTRAP_SAMPLES, len(pos)))]
    n = neg[rng.integers(len(neg), size=(BOOTSTRAP_SAMPLES, len(neg)))]
    from scipy.stats import rankdata
    ranks = rankdata(np.concatenate([p, n], axis=1), axis=1)
    u = ranks[:, : len(pos)].sum(axis=1) - len(pos) * (len(pos) + 1) / 2.0
    aucs = u / (len(pos) * len(neg))
    lo, hi = np.quantile(aucs, [(1 - level) / 2, (1 + level) / 2])
    return float(lo), float(hi)


def roc_curve(pos: np.ndarray, neg: np.ndarray) -> list[tuple[float, float]]:
    """ROC points ``(FPR, TPR)`` for every threshold "suspicion >= t", from (0, 0) to (1, 1)."""
    if len(pos) == 0 or len(neg) == 0:
        return []
    thresholds = np.unique(np.concatenate([pos, neg]))[::-1]
    tpr = (pos[None, :] >= thresholds[:, None]).mean(axis=1)
    fpr = (neg[None, :] >= thresholds[:, None]).mean(axis=1)
    return [(0.0, 0.0)] + [(float(f), float(t)) for f, t in zip(fpr, tpr)]


def tpr_at_fpr(curve: Sequence[tuple[float, float]], target: float) -> float | None:
    """Highest true-positive rate of a threshold whose false-positive rate is at most ``target``."""
    ok = [t for f, t in curve if f <= target + 1e-12]
    return max(ok) if ok else None


@dataclass(frozen=True)
class Rate:
    """A proportion ``k / n`` with its Clopper-Pearson 95 % interval."""

    k: int
    n: int
    value: float | None
    ci: tuple[float, float] | None


def rate(k: int, n: int) -> Rate:
    """``k / n`` with the exact (Clopper-Pearson) 95 % interval; None values when ``n`` is 0."""
    k, n = int(k), int(n)
    if n == 0:
        return Rate(k, n, None, None)
    from scipy.stats import beta
    lo = 0.0 if k == 0 else float(beta.ppf(0.025, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(0.975, k + 1, n - k))
    return Rate(k, n, k / n, (lo, hi))


def mcc(pred: np.ndarray, truth: np.ndarray) -> float:
    """Matthews correlation of two boolean maps of the same shape (0 when undefined)."""
    tp = float(np.count_nonzero(pred & truth))
    fp = float(np.count_nonzero(pred & ~truth))
    fn = float(np.count_nonzero(~pred & truth))
    tn = float(pred.size) - tp - fp - fn
    denom = math.sqrt((tp + fp) * (tp + fn) * (tn + fp) * (tn + fn))
    return 0.0 if denom == 0 else (tp * tn - fp * fn) / denom


def f1(pred: np.ndarray, truth: np.ndarray) -> float:
    """Pixel F1 (Dice) of two boolean maps: 2 TP / (2 TP + FP + FN), 0 when both are empty."""
    both = np.count_nonzero(pred) + np.count_nonzero(truth)
    return 0.0 if both == 0 else float(2 * np.count_nonzero(pred & truth) / both)


def iou(pred: np.ndarray, truth: np.ndarray) -> float:
    """Intersection over union of two boolean maps (0 when both are empty)."""
    union = np.count_nonzero(pred | truth)
    return 0.0 if union == 0 else float(np.count_nonzero(pred & truth) / union)


def suspicion(p_value: float | None, score: float | None, decided: bool) -> float:
    """The ranking value of one result, as this module's docstring defines it."""
    if not decided:
        return 0.0
    if p_value is not None:
        return -math.log10(max(p_value, 1e-300))
    return score if score is not None else 0.0
