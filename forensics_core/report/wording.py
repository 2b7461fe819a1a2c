"""The words the report uses for outcomes and their strength, and the scale behind them.

The outcome is one of the three an examiner may state. Its strength is read
off a fixed verbal scale that depends only on the numbers the fusion policy
used, so the words are never stronger than the numbers: a test that did not
reject the hypothesis of an original gives at most *limited* support to it,
because not finding a trace is not proof that there is none.

The scale is stated in the report. It grades the verdict's own decision
p-value (for the default policy the smallest Bonferroni-adjusted p-value; for
``fisher`` the combined p-value) against the verdict's level; it is not a
likelihood-ratio scale (such as ENFSI's), since the detectors do not yet
report likelihood ratios. A policy that states no p-value is not graded.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..findings import Role, Status, Verdict, VerdictLabel

OUTCOME_WORDS = {
    VerdictLabel.CONSISTENT: "consistent with an original",
    VerdictLabel.INCONSISTENT: "inconsistent with an original",
    VerdictLabel.INCONCLUSIVE: "inconclusive",
}

ROLE_WORDS = {
    Role.DROVE: "drove the verdict",
    Role.COUNTED: "counted",
    Role.ADVISORY: "observations only, not counted",
    Role.NOT_COUNTED: "not counted",
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


# Fixed before any data is seen: the decision level and tenfold and
# hundredfold stricter ones.
def scale(alpha: float) -> tuple[ScaleStep, ...]:
    """The verbal scale for a verdict decided at level ``alpha``."""
    return (
        ScaleStep("strong support for manipulation", f"decision p-value below {alpha / 100:g}"),
        ScaleStep("moderately strong support for manipulation", f"decision p-value below {alpha / 10:g}"),
        ScaleStep("moderate support for manipulation", f"decision p-value below {alpha:g} (the decision level)"),
        ScaleStep("limited support for an original",
                  f"at least one test ran and the decision p-value did not reach {alpha:g}; a test that does not "
                  "reject cannot prove an original"),
        ScaleStep("no support either way", "no detector produced a test result"),
    )


@dataclass(frozen=True)
class Strength:
    """The strength statement of the summary."""

    words: str
    basis: str
    graded: bool


def strength(verdict: Verdict) -> Strength:
    """Grade the verdict on :func:`scale`; a verdict without a decision p-value and level is not graded."""
    if verdict.alpha is None:
        return Strength("not graded", f"the fusion policy {verdict.policy!r} defines no verbal scale", False)
    steps = scale(verdict.alpha)
    if verdict.p_value is None:
        step = steps[4] if verdict.label is VerdictLabel.INCONCLUSIVE else None
        if step is None:
            return Strength("not graded", f"the fusion policy {verdict.policy!r} gave no decision p-value", False)
        return Strength(step.words, step.condition, True)
    basis = f"decision p-value {verdict.p_value:.3g} under the {verdict.policy} policy"
    if verdict.label is VerdictLabel.INCONSISTENT:
        a = verdict.alpha
        step = steps[0] if verdict.p_value < a / 100 else steps[1] if verdict.p_value < a / 10 else steps[2]
    else:
        step = steps[3]
    return Strength(step.words, basis, True)
