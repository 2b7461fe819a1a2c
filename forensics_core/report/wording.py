"""The words the report uses for outcomes and their strength, and the scale behind them.

The outcome is one of the three an examiner may state. Its strength is read
off a fixed verbal scale that depends only on the numbers the fusion policy
used, so the words are never stronger than the numbers: a test that did not
reject the hypothesis of an original gives at most *limited* support to it,
because not finding a trace is not proof that there is none.

The scale is stated in the report. It grades the smallest
Bonferroni-adjusted p-value; it is not a likelihood-ratio scale (such as
ENFSI's), since the detectors do not yet report likelihood ratios.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..findings import DetectorFinding, Status, Verdict, VerdictLabel
from ..fusion import ALPHA, POLICY, _p

OUTCOME_WORDS = {
    VerdictLabel.CONSISTENT: "consistent with an original",
    VerdictLabel.INCONSISTENT: "inconsistent with an original",
    VerdictLabel.INCONCLUSIVE: "inconclusive",
}

STATUS_WORDS = {
    Status.OK: "test ran",
    Status.INCONCLUSIVE: "inconclusive",
    Status.ERROR: "failed",
    Status.SKIPPED: "skipped",
}


@dataclass(frozen=True)
class ScaleStep:
    """One step of the verbal scale: the words and the condition that earns them."""

    words: str
    condition: str


# Fixed before any data is seen; the thresholds are the fusion level and
# tenfold and hundredfold stricter ones.
SCALE = (
    ScaleStep("strong support for manipulation", f"smallest adjusted p-value below {ALPHA / 100:g}"),
    ScaleStep("moderately strong support for manipulation", f"smallest adjusted p-value below {ALPHA / 10:g}"),
    ScaleStep("moderate support for manipulation", f"smallest adjusted p-value below {ALPHA:g} (the decision level)"),
    ScaleStep("limited support for an original",
              f"at least one test ran and none reached the {ALPHA:g} level; a test that does not reject cannot prove "
              "an original"),
    ScaleStep("no support either way", "no detector produced a test result"),
)


@dataclass(frozen=True)
class Strength:
    """The strength statement of the summary."""

    words: str
    basis: str
    graded: bool


def strength(verdict: Verdict, findings: Sequence[DetectorFinding]) -> Strength:
    """Grade the verdict on :data:`SCALE`; other fusion policies are not graded."""
    if verdict.policy != POLICY:
        return Strength("not graded", f"the fusion policy {verdict.policy!r} defines no verbal scale", False)
    tests = [p for f in findings if f.status is Status.OK and (p := _p(f)) is not None]
    if not tests:
        step = SCALE[4]
        return Strength(step.words, step.condition, True)
    best = min(1.0, len(tests) * min(tests))
    basis = f"smallest Bonferroni-adjusted p-value {best:.3g} over {len(tests)} test(s)"
    if verdict.label is VerdictLabel.INCONSISTENT:
        step = SCALE[0] if best < ALPHA / 100 else SCALE[1] if best < ALPHA / 10 else SCALE[2]
    else:
        step = SCALE[3]
    return Strength(step.words, basis, True)
