"""The built-in fusion policies: how detector findings become the verdict.

Registered by the core itself as implementations of ``forensics_fuse``; a
plugin may provide others under their own names (``--fusion NAME``).

Both policies take from each detector with status ``ok`` one p-value under
the null hypothesis "the photo is an original": its p-value, or, for a
detector that reports only an NFA, ``min(1, NFA)``, an upper bound on its
p-value under its a-contrario model. Detectors that ran but state no test
(metadata observations) are *advisory*; inconclusive, skipped and failed
detectors are *not counted*. Neither counts for either side. The level
:data:`ALPHA` is fixed here, before any data are seen.

``bonferroni`` (default). With m tests, each p-value is adjusted to
``min(1, m p)``; the photo is called *inconsistent with an original* when the
smallest adjusted p-value is below ALPHA, and the detectors below it drove the
verdict. It needs no assumption about how the detectors depend on each other,
which is why it is the default: the traces (lens, JPEG grid, demosaicing) are
different, but a resize or recompression affects several of them at once.
Its level holds on real photos only if each detector's own null does; both
are measured on real authentic photos by ``forensics validate`` (the page's
null checks), together with the detectors' pairwise rank dependence
(:mod:`.validation.dependence`), which tells whether Fisher's rule may be used.

``fisher``. Fisher's combined statistic ``X = -2 sum(ln p_i)`` follows a
chi-squared law with 2m degrees of freedom when the m tests are independent;
the photo is called inconsistent when its upper-tail p-value is below ALPHA.
More powerful than Bonferroni when several detectors see weak traces, but
valid only under independence; the drivers are the fewest tests, smallest
p-values first, whose statistic alone already rejects.

Under either, the photo is called *consistent with an original* only when at
least one test ran and the combination did not reject; otherwise the verdict
is *inconclusive*.

``likelihood_ratio``. The label follows the fused likelihood ratio of the
calibrated detectors (:mod:`.evaluation`), with thresholds fixed here:
*inconsistent with an original* when LR >= 10 ** :data:`LR_DECISION_LOG10`,
*consistent* when LR <= 10 ** -LR_DECISION_LOG10, *inconclusive* in between
or without calibrators. This hook only names the policy; the label is set
once the likelihood ratios are computed.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from .hookspecs import hookimpl
from .findings import Contribution, DetectorFinding, Role, Status, Verdict, VerdictLabel

POLICY = "bonferroni"
ALPHA = 0.01
LR_POLICY = "likelihood_ratio"
LR_DECISION_LOG10 = 2.0

# p-values below this are floored before taking logarithms (Fisher) so that a
# detector reporting p = 0 gives a finite, still overwhelming, statistic.
_P_FLOOR = 1e-300


def finding_p(finding: DetectorFinding) -> float | None:
    """The p-value a policy takes from one finding, or None when it states no test."""
    if finding.p_value is not None:
        return finding.p_value
    if finding.nfa is not None:
        return min(1.0, finding.nfa)
    return None


def _split(findings: Sequence[DetectorFinding]) -> tuple[list[tuple[str, float]], list[Contribution]]:
    tests, idle = [], []
    for f in findings:
        p = finding_p(f)
        if f.status is Status.OK and p is not None:
            tests.append((f.name, p))
        else:
            idle.append(Contribution(f.name, Role.ADVISORY if f.status is Status.OK else Role.NOT_COUNTED))
    return tests, idle


def _idle_note(idle: Sequence[Contribution], findings: Sequence[DetectorFinding]) -> str:
    status = {f.name: f.status.value for f in findings}
    parts = [f"{c.detector} ({'no p-value' if c.role is Role.ADVISORY else status[c.detector]})" for c in idle]
    return f" Not counted either way: {', '.join(parts)}." if parts else ""


def _no_test(policy: str, method: str, idle: Sequence[Contribution], findings: Sequence[DetectorFinding]) -> Verdict:
    return Verdict(
        label=VerdictLabel.INCONCLUSIVE,
        score=None,
        explanation="No detector produced a test result, so nothing can be said either way." + _idle_note(idle, findings),
        policy=policy,
        alpha=ALPHA,
        method=method,
        contributions=list(idle),
    )


BONFERRONI_METHOD = (f"Bonferroni over the detectors that ran a test: each p-value times the number of tests, "
                     f"compared with {ALPHA:g}; valid whatever the dependence between detectors.")
FISHER_METHOD = (f"Fisher's combination -2 sum(ln p) against chi-squared with 2m degrees of freedom, compared with "
                 f"{ALPHA:g}; valid only if the detectors' tests are independent.")


def bonferroni(findings: Sequence[DetectorFinding], alpha: float = ALPHA) -> Verdict:
    """Fuse findings by the ``bonferroni`` rule of this module's docstring."""
    tests, idle = _split(findings)
    if not tests:
        return _no_test("bonferroni", BONFERRONI_METHOD, idle, findings)
    m = len(tests)
    adjusted = {name: min(1.0, m * p) for name, p in tests}
    best = min(adjusted.values())
    rejecting = sorted(n for n, q in adjusted.items() if q < alpha)
    if rejecting:
        label, drivers = VerdictLabel.INCONSISTENT, rejecting
        text = (f"{', '.join(rejecting)} rejected the hypothesis of an original at the {alpha:g} level after "
                f"Bonferroni adjustment over {m} test(s) (smallest adjusted p = {best:.3g}).")
    else:
        label, drivers = VerdictLabel.CONSISTENT, sorted(adjusted)
        text = (f"None of the {m} test(s) ({', '.join(sorted(adjusted))}) rejected the hypothesis of an original "
                f"at the {alpha:g} level after Bonferroni adjustment (smallest adjusted p = {best:.3g}); "
                "not rejecting it is no evidence that the photo is an original.")
    contributions = [Contribution(n, Role.DROVE if n in drivers else Role.COUNTED, p, adjusted[n]) for n, p in tests]
    return Verdict(label=label, score=1.0 - best, explanation=text + _idle_note(idle, findings), policy="bonferroni",
                   drivers=drivers, p_value=best, alpha=alpha, method=BONFERRONI_METHOD,
                   contributions=contributions + idle)


def fisher_p(p_values: Sequence[float]) -> float:
    """Fisher's combined p-value of independent tests: P(chi2(2m) >= -2 sum ln p)."""
    stat = -2.0 * sum(math.log(max(p, _P_FLOOR)) for p in p_values)
    from scipy.special import chdtrc

    return float(chdtrc(2 * len(p_values), stat))


def fisher(findings: Sequence[DetectorFinding], alpha: float = ALPHA) -> Verdict:
    """Fuse findings by the ``fisher`` rule of this module's docstring."""
    tests, idle = _split(findings)
    if not tests:
        return _no_test("fisher", FISHER_METHOD, idle, findings)
    m = len(tests)
    combined = fisher_p([p for _, p in tests])
    ordered = sorted(tests, key=lambda t: t[1])
    if combined < alpha:
        k = next(k for k in range(1, m + 1) if fisher_p([p for _, p in ordered[:k]] + [1.0] * (m - k)) < alpha)
        drivers = sorted(n for n, _ in ordered[:k])
        label = VerdictLabel.INCONSISTENT
        text = (f"Fisher's combination of {m} independent test(s) rejected the hypothesis of an original at the "
                f"{alpha:g} level (combined p = {combined:.3g}), driven by {', '.join(drivers)}.")
    else:
        drivers = sorted(n for n, _ in tests)
        label = VerdictLabel.CONSISTENT
        text = (f"Fisher's combination of the {m} test(s) ({', '.join(drivers)}) did not reject the hypothesis of an "
                f"original at the {alpha:g} level (combined p = {combined:.3g}); not rejecting it is no evidence "
                "that the photo is an original.")
    contributions = [Contribution(n, Role.DROVE if n in drivers else Role.COUNTED, p, None) for n, p in tests]
    return Verdict(label=label, score=1.0 - combined, explanation=text + _idle_note(idle, findings), policy="fisher",
                   drivers=drivers, p_value=combined, alpha=alpha, method=FISHER_METHOD,
                   contributions=contributions + idle)


LR_METHOD = (f"the fused likelihood ratio of the calibrated detectors: labelled inconsistent when it is at least "
             f"{10 ** LR_DECISION_LOG10:g}, consistent when at most 1/{10 ** LR_DECISION_LOG10:g}, inconclusive in "
             f"between.")


def likelihood_ratio(findings: Sequence[DetectorFinding]) -> Verdict:
    """The ``likelihood_ratio`` policy before the LRs are known: inconclusive until :mod:`.evaluation` decides."""
    _, idle = _split(findings)
    counted = [Contribution(f.name, Role.COUNTED) for f in findings if f.name not in {c.detector for c in idle}]
    return Verdict(label=VerdictLabel.INCONCLUSIVE, score=None, explanation="No likelihood ratio was computed.",
                   policy=LR_POLICY, method=LR_METHOD, contributions=counted + idle)


POLICIES: dict[str, Callable[[Sequence[DetectorFinding]], Verdict]] = {
    "bonferroni": bonferroni, "fisher": fisher, LR_POLICY: likelihood_ratio}


@hookimpl
def forensics_fuse(policy: str, findings: Sequence[DetectorFinding]) -> Verdict | None:
    rule = POLICIES.get(policy)
    return rule(findings) if rule is not None else None
