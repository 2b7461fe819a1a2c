"""The built-in fusion policy: Bonferroni over the detectors that ran.

Registered by the core itself as the implementation of ``forensics_fuse`` for
policy ``bonferroni``; a plugin may provide others under their own names.

Rule. Let the detectors with status ``ok`` and a p-value be the m tests (a
detector that reports only an NFA contributes ``min(1, NFA)``, an upper bound
on its p-value under its a-contrario model). The photo is called
*inconsistent with an original* when some detector's adjusted p-value
``min(1, m * p)`` is below :data:`ALPHA`, fixed here before any data is seen.
It is called *consistent* only when at least one such test ran and none
rejected; otherwise *inconclusive*. Inconclusive, skipped and failed detectors
count for neither side. Bonferroni needs no independence between detectors.
"""

from __future__ import annotations

from collections.abc import Sequence

from . import hookimpl
from .findings import DetectorFinding, Status, Verdict, VerdictLabel

POLICY = "bonferroni"
ALPHA = 0.01


def _p(finding: DetectorFinding) -> float | None:
    if finding.p_value is not None:
        return finding.p_value
    if finding.nfa is not None:
        return min(1.0, finding.nfa)
    return None


def bonferroni(findings: Sequence[DetectorFinding], alpha: float = ALPHA) -> Verdict:
    """Fuse findings by the rule in this module's docstring."""
    tests = [(f.name, p) for f in findings if f.status is Status.OK and (p := _p(f)) is not None]
    idle = [f"{f.name} ({f.status.value})" for f in findings if f.status is not Status.OK]
    idle_note = f" Not counted: {', '.join(idle)}." if idle else ""
    if not tests:
        return Verdict(
            label=VerdictLabel.INCONCLUSIVE,
            score=None,
            explanation="No detector produced a test result, so nothing can be said either way." + idle_note,
            policy=POLICY,
        )
    m = len(tests)
    adjusted = {name: min(1.0, m * p) for name, p in tests}
    best = min(adjusted.values())
    rejecting = sorted(n for n, q in adjusted.items() if q < alpha)
    if rejecting:
        label = VerdictLabel.INCONSISTENT
        text = (
            f"{', '.join(rejecting)} rejected the hypothesis of an original at the {alpha:g} level "
            f"after Bonferroni adjustment over {m} test(s) (smallest adjusted p = {best:.3g})."
        )
        drivers = rejecting
    else:
        label = VerdictLabel.CONSISTENT
        text = (
            f"None of the {m} test(s) ({', '.join(sorted(adjusted))}) rejected the hypothesis of an original "
            f"at the {alpha:g} level after Bonferroni adjustment (smallest adjusted p = {best:.3g}); "
            "this is consistent with an original, not proof of one."
        )
        drivers = sorted(adjusted)
    return Verdict(label=label, score=1.0 - best, explanation=text + idle_note, policy=POLICY, drivers=drivers)


@hookimpl
def forensics_fuse(policy: str, findings: Sequence[DetectorFinding]) -> Verdict | None:
    return bonferroni(findings) if policy == POLICY else None
