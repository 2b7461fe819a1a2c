"""The words the report uses: the evaluative statement, the screening line, and the strength scale.

The report's headline is the evaluative statement: the fused likelihood
ratio of the findings for two stated propositions (:mod:`..evaluation`), in
numbers and in ENFSI's verbal equivalents (ENFSI Guideline for Evaluative
Reporting in Forensic Science, 2015). The fusion policy's label (a triage at
a level fixed in advance) is stated below it as what it is, an
investigative screen: a p-value is never graded as support, and not
rejecting an original is not evidence for one, so the report never calls a
photo consistent with an original.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..calibration.model import supports
from ..containment import one_line
from ..findings import HEADLINE_WORDS, DetectorFinding, Role, Status, Verdict, VerdictLabel
from ..fusion import LR_DECISION_LOG10, LR_POLICY

HP_SHORT = "content was inserted, moved or removed"
"""Hp in the headline's words; the full proposition is stated under it."""

HD_SHORT = "the photo is as the camera produced it, or was only processed as a whole"
"""Hd in the headline's words (processing of the whole frame that changes no content stays under Hd)."""

ROLE_WORDS = {
    Role.DROVE: "drove the screen",
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


@dataclass(frozen=True)
class Statement:
    """The evaluative statement that heads the report (and each row of a batch index).

    Attributes
    ----------
    sentence : str
        The fused likelihood ratio as a sentence about the two propositions.
    verbal : str
        ENFSI's words for it ("moderate support for Hp (manipulation)").
    lr : str
        The likelihood ratio to three significant figures, or "—" when none was computed.
    side : int
        1 where the words support Hp, -1 Hd, 0 neither (:func:`..calibration.model.supports`).
    bounds : str or None
        The range of likelihood ratios its calibration data can support (ELUB bounds), in words.
    """

    sentence: str
    verbal: str
    lr: str
    side: int
    bounds: str | None


def _figure(value: float) -> str:
    """A positive number to three significant figures, large ones written out: 1270, not 1.27e+03."""
    return f"{value:.3g}" if value < 1000.0 else f"{float(f'{value:.3g}'):,.0f}"


def lr_text(log10_lr: float) -> str:
    """A likelihood ratio as a reader takes it in: 0.912, 21.9, 1,270; below 1/1000 as 1/1,270."""
    value = 10.0 ** log10_lr
    return _figure(value) if value >= 1e-3 else f"1/{_figure(1.0 / value)}"


def _ratio(log10_value: float) -> str:
    value = 10.0 ** log10_value
    return _figure(value) if value >= 1.0 else f"1/{_figure(1.0 / value)}"


def statement(verdict: Verdict) -> Statement:
    """The fused likelihood ratio of ``verdict`` as the report's headline statement."""
    lr = verdict.likelihood_ratio
    if lr is None or lr.log10_lr is None:
        return Statement("The findings were not evaluated: no calibrated detector covers this photo, so no likelihood "
                         "ratio can be stated.", "not evaluated", "—", 0, None)
    side = supports(lr.log10_lr)
    times = _figure(10.0 ** abs(lr.log10_lr))
    if side > 0:
        sentence = f"The findings are about {times} times more probable if {HP_SHORT} than if {HD_SHORT}."
    elif side < 0:
        sentence = f"The findings are about {times} times more probable if {HD_SHORT} than if {HP_SHORT}."
    else:
        sentence = f"The findings are about as probable if {HP_SHORT} as if {HD_SHORT}."
    elub = lr.calibration.get("elub_fused")
    bounds = (f"Its calibration data support likelihood ratios from {_ratio(elub[0])} to {_ratio(elub[1])} "
              f"(ELUB bounds)." if elub else None)
    own = sorted(lr.calibration.get("own_calibration") or {})
    if bounds and own:
        # Their LR is multiplied into the fused one, so the statement may lie outside the fused bounds.
        bounds = (f"Its calibration data support likelihood ratios from {_ratio(elub[0])} to {_ratio(elub[1])} "
                  f"(ELUB bounds) for the detectors fused; the likelihood ratio of {', '.join(own)}, calibrated on "
                  f"{'its' if len(own) == 1 else 'their'} own data within {'its' if len(own) == 1 else 'their'} own "
                  f"bounds, is multiplied into it, so the statement may lie beyond that range.")
    return Statement(sentence, lr.verbal, lr_text(lr.log10_lr), side, bounds)


def screening(verdict: Verdict, where: bool = True) -> str:
    """The fusion policy's triage in one line, named as the investigative screen it is.

    ``where``: a rejection points the reader to page 1's Where figure (not in a batch index, which has none).
    """
    label = verdict.label
    if verdict.policy == LR_POLICY:
        threshold = f"{10 ** LR_DECISION_LOG10:g}"
        return {
            VerdictLabel.INCONSISTENT: f"Screening (likelihood ratio): the fused likelihood ratio reached {threshold}.",
            VerdictLabel.CONSISTENT: f"Screening (likelihood ratio): the fused likelihood ratio fell to 1/{threshold}.",
            VerdictLabel.INCONCLUSIVE: f"Screening (likelihood ratio): the fused likelihood ratio stayed between "
                                       f"1/{threshold} and {threshold}.",
        }[label]
    tested = [c for c in verdict.contributions if c.role in (Role.DROVE, Role.COUNTED)]
    level = f"{verdict.alpha:.0%}" if verdict.alpha is not None else "its stated level"
    if label is VerdictLabel.INCONCLUSIVE or not tested:
        return "Screening: no detector could test the photo; nothing was screened."
    if label is VerdictLabel.CONSISTENT:
        return (f"Screening: no detector rejected its null at the {level} level ({verdict.policy}, "
                f"{len(tested)} test{'s' if len(tested) != 1 else ''}).")
    drove = [c for c in verdict.contributions if c.role is Role.DROVE]
    named = ", ".join(f"{c.detector} (adjusted p = {c.adjusted_p:.2g})" if c.adjusted_p is not None else c.detector
                      for c in drove)
    return (f"Screening: {named} rejected {'its' if len(drove) == 1 else 'their'} null at the {level} level "
            f"({verdict.policy}){'; see Where' if where else ''}.")


def found_something(finding: DetectorFinding, verdict: Verdict) -> bool:
    """Whether ``finding`` is one the reader must look at: it drove a rejecting screen, or its own LR supports Hp.

    A detector's map alone is not enough: some list the area that departs
    most even when it departs no more than in originals.
    """
    drove = verdict.label is VerdictLabel.INCONSISTENT and any(
        c.detector == finding.name and c.role is Role.DROVE for c in verdict.contributions)
    return drove or supports(finding.log10_lr) > 0


_SENTENCE_END = re.compile(r"(?<=[.!?])\s+(?=[A-Z0-9(\"'])")


def row_sentence(finding: DetectorFinding) -> str:
    """The finding in at most :data:`HEADLINE_WORDS` words, for its row on page 1 and in a batch index.

    The plugin's ``headline`` where it keeps to the length; otherwise the
    first sentence of its summary (a failure: its error), cut to the length
    with an ellipsis, the rest being in the detector's appendix.
    """
    given = " ".join((finding.headline or "").split())
    if given and len(given.split()) <= HEADLINE_WORDS:
        return given
    if finding.status is Status.ERROR and finding.error:
        text = f"Failed: {one_line(finding.error)}"
    else:
        text = _SENTENCE_END.split(" ".join(finding.summary.split()), maxsplit=1)[0]
    words = text.split()
    return text if len(words) <= HEADLINE_WORDS else " ".join(words[:HEADLINE_WORDS - 1]) + " …"
