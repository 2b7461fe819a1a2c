"""The "Known error rates" section: figures from a validation record, matched to this report's detectors."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..findings import Findings
from ..validation.metrics import Rate
from ..validation.record import VERDICT, MethodMetrics, ValidationRecord


@dataclass(frozen=True)
class RateRow:
    """One detector's (or the verdict's) measured figures, as text."""

    name: str
    measured_version: str
    auc: str
    tpr_at_5: str
    tpr_at_1: str
    rule: str
    tpr: str
    fpr: str
    declined: str
    n: str


@dataclass(frozen=True)
class ErrorRates:
    """What the section shows; ``record`` None means no figures could be stated."""

    source: str
    record: ValidationRecord | None
    rows: list[RateRow] = field(default_factory=list)
    cautions: list[str] = field(default_factory=list)


def _pct(r: Rate) -> str:
    if r.value is None:
        return "—"
    return f"{100 * r.value:.1f}% ({r.k}/{r.n}; 95% CI {100 * r.ci[0]:.1f}–{100 * r.ci[1]:.1f}%)"


def _row(m: MethodMetrics, name: str) -> RateRow:
    auc = "—" if m.auc is None else f"{m.auc:.3f}" + (f" ({m.auc_ci[0]:.3f}–{m.auc_ci[1]:.3f})" if m.auc_ci else "")
    t5, t1 = m.tpr_at_fpr.get("0.05"), m.tpr_at_fpr.get("0.01")
    declined = Rate(m.declined_spliced.k + m.declined_authentic.k, m.n_spliced + m.n_authentic, None, None)
    n = declined.n
    return RateRow(
        name=name, measured_version=m.version, auc=auc,
        tpr_at_5="—" if t5 is None else f"{100 * t5:.0f}%", tpr_at_1="—" if t1 is None else f"{100 * t1:.0f}%",
        rule=m.operating_point.rule, tpr=_pct(m.operating_point.tpr), fpr=_pct(m.operating_point.fpr),
        declined="—" if n == 0 else f"{100 * declined.k / n:.0f}%", n=f"{m.n_spliced} + {m.n_authentic}",
    )


def error_rates(findings: Findings, record: ValidationRecord | None, source: str) -> ErrorRates:
    """Match ``record`` to ``findings``: one row per detector of this run, then the verdict, with cautions.

    A caution is stated when the record was made with another tool version,
    another version of a detector or another fusion policy, or does not
    cover a detector of this run: the figures then describe a different method.
    """
    if record is None:
        return ErrorRates(source, None)
    rows, cautions = [], []
    if record.tool.get("version") != findings.tool.version:
        cautions.append(f"The figures were measured with forensics {record.tool.get('version')}; this report was made "
                        f"with {findings.tool.version}.")
    for f in findings.detectors:
        m = record.method(f.name)
        if m is None:
            cautions.append(f"{f.name}: not covered by this validation record; no error rate can be stated for it.")
            continue
        if m.version != f.version:
            cautions.append(f"{f.name}: measured at version {m.version}, run here at version {f.version}.")
        rows.append(_row(m, f.name))
    verdict = record.method(VERDICT)
    if verdict is not None:
        measured = sorted(m.name for m in record.methods if m.name != VERDICT)
        ran = sorted(f.name for f in findings.detectors)
        if measured != ran:
            cautions.append(f"The fused verdict's figures combine {', '.join(measured) or 'no detector'}; this report "
                            f"combines {', '.join(ran) or 'no detector'}.")
        if record.fusion.get("policy") != findings.verdict.policy:
            cautions.append(f"The fused verdict's figures are for the {record.fusion.get('policy')} policy; this report "
                            f"used {findings.verdict.policy}.")
        rows.append(_row(verdict, "fused verdict"))
    return ErrorRates(source, record, rows, cautions)
