"""The words the report uses for outcomes and for the strength of the evidence.

The outcome is one of the three an examiner may state, decided by the fusion
policy at a level fixed in advance (a triage decision). The strength of the
evidence is a separate statement: the likelihood ratio of the findings for
two stated propositions (:mod:`..evaluation`), in ENFSI's verbal equivalents
(ENFSI Guideline for Evaluative Reporting in Forensic Science, 2015). A
p-value is never graded as support: not rejecting an original is not
evidence for one, and only a calibrated LR says how much the findings favour
either proposition.
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
    Role.ADVISORY: "no p-value, not counted",
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
    """One step of the verbal scale: the words and the likelihood ratios that earn them."""

    words: str
    condition: str


# ENFSI (2015), for LRs above 1; the same words for support of Hd when the LR
# is below 1 (its reciprocal in the condition).
SCALE = (
    ScaleStep("extremely strong support", "LR 1,000,000 or more"),
    ScaleStep("very strong support", "LR 10,000 to 1,000,000"),
    ScaleStep("strong support", "LR 1,000 to 10,000"),
    ScaleStep("moderately strong support", "LR 100 to 1,000"),
    ScaleStep("moderate support", "LR 10 to 100"),
    ScaleStep("weak support", "LR 2 to 10"),
    ScaleStep("no support for either proposition", "LR between 1/2 and 2"),
)


def scale() -> tuple[ScaleStep, ...]:
    """The verbal scale the report states (for LRs below 1 the same words apply to Hd, with 1/LR)."""
    return SCALE


@dataclass(frozen=True)
class Strength:
    """The strength statement of the summary."""

    words: str
    basis: str
    graded: bool


def lr_words(log10_lr: float) -> str:
    """'about N times more (or less) probable' for a log10 LR."""
    lr = 10.0 ** log10_lr
    if lr >= 1.0:
        return f"about {lr:.3g} times more probable"
    return f"about {1.0 / lr:.3g} times less probable"


def strength(verdict: Verdict) -> Strength:
    """The verdict's likelihood ratio in words; not graded when no calibrated LR was computed."""
    lr = verdict.likelihood_ratio
    if lr is None or lr.log10_lr is None:
        return Strength("not evaluated", "no calibrated likelihood ratio: the installed calibrators do not cover "
                        "these detectors", False)
    return Strength(lr.verbal, f"fused likelihood ratio {10.0 ** lr.log10_lr:.3g} (log10 {lr.log10_lr:+.2f})", True)
