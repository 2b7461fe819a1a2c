"""Does each detector's null hold on authentic photos?

A detector's p-value is valid when, on photos for which its null hypothesis
("an original") is true, ``P(p <= t) <= t`` for every level ``t``: its
empirical CDF over authentic photos lies on or below the diagonal. This
module computes that curve, a test of the departure above the diagonal, how
often each method convicts an authentic photo at the rule the verdict uses,
and per-set figures, all from the record's per-photo rows
(:func:`.record.case_rows`), so they can be recomputed from any record.

References
----------
.. [1] R. H. Berk and D. H. Jones, "Goodness-of-fit test statistics that
   dominate the Kolmogorov statistics", Z. Wahrscheinlichkeitstheorie verw.
   Gebiete 47 (1979) 47-59.
.. [2] H. A. David and H. N. Nagaraja, *Order Statistics*, 3rd ed., Wiley,
   2003, sec. 2.2 (the k-th of n uniform order statistics is Beta(k, n-k+1)).
.. [3] C. J. Clopper and E. S. Pearson, "The use of confidence or fiducial
   limits illustrated in the case of the binomial", Biometrika 26 (1934)
   404-413.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..fusion import ALPHA
from .cases import SET_CONDITION
from .metrics import Rate, auc_bootstrap_ci, rate, roc_auc, suspicion

NULL_LEVELS = (0.01, 0.001)
"""Levels at which the share of authentic photos with ``p <= level`` is recorded."""

VERDICT = "verdict"
"""Name under which the fused verdict's figures are recorded, beside the detectors'."""

VERDICT_RULE = "the screen rejected (fusion label inconsistent)"
"""The fused verdict's operating point: the fusion policy's screen rejected the photo's null."""

_NO_SET = "(no set)"


def ecdf(p_values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Empirical CDF of p-values at each distinct observed value.

    Parameters
    ----------
    p_values : ndarray, shape (n,)
        p-values in [0, 1].

    Returns
    -------
    x : ndarray, shape (m,)
        The distinct values, ascending.
    y : ndarray, shape (m,)
        Share of ``p_values`` at or below each ``x``; a valid test has ``y <= x``
        up to sampling noise.
    """
    p = np.sort(np.asarray(p_values, dtype=float))
    x = np.unique(p)
    return x, np.searchsorted(p, x, side="right") / max(1, len(p))


def superuniformity_p(p_values: np.ndarray) -> float | None:
    """p-value of the hypothesis that ``p_values`` are super-uniform (``P(p <= t) <= t``).

    The k-th smallest of n uniform values follows Beta(k, n-k+1) [2]_, so
    ``B_k(p_(k))`` (its CDF at the observed k-th smallest) is uniform under a
    uniform null and stochastically larger under a super-uniform one. A test
    that convicts too often makes some ``B_k`` small; the smallest of the n,
    times n (a union bound), is a valid p-value whatever the dependence
    between order statistics. This is the Berk-Jones idea [1]_ with a
    conservative calibration; it weighs the tail (small p), where the
    Kolmogorov statistic is blind.

    Parameters
    ----------
    p_values : ndarray, shape (n,)

    Returns
    -------
    float or None
        In [0, 1]; None when there are no values.
    """
    p = np.sort(np.asarray(p_values, dtype=float))
    n = len(p)
    if n == 0:
        return None
    k = np.arange(1, n + 1)
    from scipy.stats import beta
    return float(min(1.0, n * beta.cdf(p, k, n - k + 1).min()))


def pointwise_limit(x: np.ndarray, n: int, level: float = 0.95) -> np.ndarray:
    """Upper ``level`` limit of the empirical CDF of ``n`` uniform values at each ``x`` (binomial quantile / n).

    Parameters
    ----------
    x : ndarray, shape (m,)
    n : int

    Returns
    -------
    ndarray, shape (m,)
    """
    from scipy.stats import binom
    return binom.ppf(level, n, np.clip(x, 0.0, 1.0)) / max(1, n)


@dataclass
class SetFigures:
    """One method on the photos of one set: ranking, false convictions at the rule, declines."""

    set: str
    n_spliced: int
    n_authentic: int
    auc: float | None
    auc_ci: tuple[float, float] | None
    fpr: Rate
    declined: Rate


@dataclass
class NullCheck:
    """One method's behaviour on the authentic photos.

    ``n_tested`` authentic photos had a p-value (it did not decline); ``below``
    holds, per level of :data:`NULL_LEVELS`, the share of those with
    ``p <= level``; ``convicted`` the share of all authentic photos taken in
    that the method convicts at ``rule``, and ``convicted_cases`` their names.
    """

    name: str
    rule: str
    n_authentic: int
    n_tested: int
    smallest_p: float | None
    below: dict[str, Rate]
    superuniformity_p: float | None
    convicted: Rate
    convicted_cases: list[str] = field(default_factory=list)
    by_set: list[SetFigures] = field(default_factory=list)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> NullCheck:
        def r(x):
            return Rate(x["k"], x["n"], x["value"], tuple(x["ci"]) if x["ci"] else None)

        return cls(**{**d, "below": {k: r(v) for k, v in d["below"].items()}, "convicted": r(d["convicted"]),
                      "by_set": [SetFigures(**{**s, "auc_ci": tuple(s["auc_ci"]) if s["auc_ci"] else None,
                                               "fpr": r(s["fpr"]), "declined": r(s["declined"])})
                                 for s in d["by_set"]]})


@dataclass(frozen=True)
class _Obs:
    """One method on one photo: its p-value (None when untested), ranking value, and whether it convicts."""

    case: str
    set: str
    spliced: bool
    p: float | None
    decided: bool
    suspicion: float
    convicts: bool


def _tests(detectors: Mapping[str, Mapping[str, Any]]) -> int:
    return sum(d.get("status") == "ok" and d.get("p_value") is not None for d in detectors.values())


def detector_rule(fusion: Mapping[str, Any]) -> str:
    """The rule at which a single detector convicts, as the record's fusion applies it."""
    alpha = fusion.get("alpha", ALPHA)
    if fusion.get("policy") == "bonferroni":
        return f"p-value times the number of tests on the photo below {alpha:g} (Bonferroni, as the verdict)"
    return f"p-value below {alpha:g} (no adjustment: the {fusion.get('policy')} policy has no per-detector rule)"


def _observations(cases: Sequence[Mapping[str, Any]], name: str, fusion: Mapping[str, Any]) -> list[_Obs]:
    alpha = fusion.get("alpha", ALPHA)
    bonferroni = fusion.get("policy") == "bonferroni"
    with_p = name == VERDICT or any(c["detectors"].get(name, {}).get("p_value") is not None for c in cases)
    out = []
    for c in cases:
        where = c.get("conditions", {}).get(SET_CONDITION, _NO_SET)
        if name == VERDICT:
            decided = c.get("verdict") not in (None, "inconclusive")
            p = c.get("verdict_p") if decided else None
            out.append(_Obs(c["name"], where, c["spliced"], p, decided, suspicion(p, None, decided),
                            c.get("verdict") == "inconsistent"))
            continue
        d = c["detectors"].get(name, {})
        decided = d.get("status") == "ok"
        p = d.get("p_value") if decided else None
        m = _tests(c["detectors"]) if bonferroni else 1
        out.append(_Obs(c["name"], where, c["spliced"], p, decided,
                        suspicion(p if with_p else None, d.get("score"), decided),
                        p is not None and m * p < alpha))
    return out


def _set_figures(obs: Sequence[_Obs]) -> list[SetFigures]:
    out = []
    for where in sorted({o.set for o in obs}):
        rows = [o for o in obs if o.set == where]
        pos = np.array([o.suspicion for o in rows if o.spliced])
        neg = np.array([o.suspicion for o in rows if not o.spliced])
        aut = [o for o in rows if not o.spliced]
        out.append(SetFigures(where, len(pos), len(neg), roc_auc(pos, neg), auc_bootstrap_ci(pos, neg),
                              rate(sum(o.convicts for o in aut), len(aut)),
                              rate(sum(not o.decided for o in rows), len(rows))))
    return out


def null_check(cases: Sequence[Mapping[str, Any]], name: str, fusion: Mapping[str, Any]) -> NullCheck:
    """The :class:`NullCheck` of detector ``name`` (or :data:`VERDICT`) over the record's rows ``cases``.

    Photos that could not be taken in are left out; a detector that declined
    on a photo contributes no p-value and convicts nothing there.
    """
    taken = [c for c in cases if c.get("error") is None]
    obs = _observations(taken, name, fusion)
    aut = [o for o in obs if not o.spliced]
    p = np.array([o.p for o in aut if o.p is not None], dtype=float)
    rule = VERDICT_RULE if name == VERDICT else detector_rule(fusion)
    return NullCheck(
        name=name, rule=rule, n_authentic=len(aut), n_tested=len(p),
        smallest_p=float(p.min()) if len(p) else None,
        below={f"{t:g}": rate(int(np.count_nonzero(p <= t)), len(p)) for t in NULL_LEVELS},
        superuniformity_p=superuniformity_p(p),
        convicted=rate(sum(o.convicts for o in aut), len(aut)),
        convicted_cases=[o.case for o in aut if o.convicts],
        by_set=_set_figures(obs),
    )


def null_checks(cases: Sequence[Mapping[str, Any]], fusion: Mapping[str, Any]) -> list[NullCheck]:
    """:func:`null_check` of every detector in ``cases`` (by name), then of the verdict."""
    names = sorted({n for c in cases if c.get("error") is None for n in c["detectors"]})
    return [null_check(cases, n, fusion) for n in [*names, VERDICT]]


def authentic_p_values(cases: Sequence[Mapping[str, Any]], name: str) -> np.ndarray:
    """The p-values of ``name`` (or :data:`VERDICT`) over the authentic photos it tested, shape (n_tested,)."""
    obs = _observations([c for c in cases if c.get("error") is None], name, {})
    return np.array([o.p for o in obs if not o.spliced and o.p is not None], dtype=float)


@dataclass(frozen=True)
class Conviction:
    """An authentic photo called inconsistent: by ``detector`` at its rule, or by the verdict alone."""

    case: str
    set: str | None
    detector: str
    p: float | None
    verdict: str | None


def convictions(cases: Sequence[Mapping[str, Any]], checks: Sequence[NullCheck]) -> list[Conviction]:
    """Every authentic photo convicted by the verdict or by a detector at its rule, in the record's order.

    One row per detector that convicts the photo; a photo the verdict alone
    convicts (possible under policies other than Bonferroni) gets one row
    under :data:`VERDICT`.
    """
    convicted = {c.name: set(c.convicted_cases) for c in checks}
    by_verdict = convicted.pop(VERDICT, set())
    out = []
    for c in cases:
        if c["spliced"] or c.get("error") is not None:
            continue
        where = c.get("conditions", {}).get(SET_CONDITION)
        names = [n for n in sorted(convicted) if c["name"] in convicted[n]]
        out += [Conviction(c["name"], where, n, c["detectors"][n].get("p_value"), c.get("verdict")) for n in names]
        if not names and c["name"] in by_verdict:
            out.append(Conviction(c["name"], where, VERDICT, c.get("verdict_p"), c.get("verdict")))
    return out
