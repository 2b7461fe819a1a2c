"""The lens distortion section of the evidence report."""

from __future__ import annotations

from importlib.resources import files
from typing import Any

from forensics_core import DetectorFinding, Evidence, Status
from forensics_core.report import Figure, ReportSection

from .spec import REFERENCES
from .figures import k1_plot_svg, line_class, overlay_png

_STATUS_WORDS = {
    "flagged": "departs",
    "strong": "|z| ≥ 2, within the test",
    "consistent": "consistent",
    "uninformative": "not informative",
}


def _num(value: float | None, fmt: str) -> str:
    return "–" if value is None else format(value, fmt)


def _line_rows(lines: list[dict[str, Any]]) -> list[dict[str, Any]]:
    rows = []
    for ln in lines:
        cls = line_class(ln)
        rows.append({
            "id": ln["id"], "distance": ln["distance"], "length_px": ln["length_px"],
            "k1_text": _num(ln["k1"], "+.4f"), "se_text": _num(ln["k1_stderr"], ".4f"),
            "paper_text": _num(ln["k1_paper"], "+.5f"), "rms_text": _num(ln["residual_rms_px"], ".2f"),
            "z_text": _num(ln["z"], "+.1f"), "css": f"line-{cls}",
            "status": "departs alone: curved or non-straight object?" if ln.get("outlier") else _STATUS_WORDS[cls],
        })
    return rows


def _region_text(region: dict[str, Any] | None) -> str | None:
    """The strongest region in words: its lines, the lens that explains them and the strength."""
    if not region:
        return None
    if region["alternative"] == "another lens":
        account = f"another lens, k1 about {region['donor_k1']:+.3f}"
    else:
        dx, dy = region["shift_px"]
        account = f"this lens about a centre displaced as by a copy moved ({round(dx):+d}, {round(dy):+d}) px"
    pasted = ", ".join(str(i) for i in region["pasted_line_ids"]) or "none of them"
    log10 = region["log10_bayes_factor"]
    if region["decided"]:
        verdict = "it decides the test"
    elif log10 is None or log10 <= 0:
        verdict = "one lens explains these lines at least as well"
    else:
        verdict = "not strong enough to decide the test against the number of regions tested"
    strength = ("its lines in one of the two directions give that account no support" if log10 is None else
                f"Bayes factor 10^{log10:.1f} against one lens")
    return (f"Strongest region: lines {', '.join(str(i) for i in region['line_ids'])}. The best other account of "
            f"them is {account}, followed by lines {pasted}; {strength} (p = {region['p_value']:.2g} for this "
            f"region, {region['n_regions']} regions tested): {verdict}.")


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one lens distortion finding: figures, tables, test, method and limitations."""
    details = finding.details
    p = details.get("p_value")
    if finding.status is Status.INCONCLUSIVE or p is None:
        decision = "no decision: too little of the trace"
    elif p < details["alpha"]:
        decision = "the lines are inconsistent with one lens"
    else:
        decision = "no significant departure"
    context = {
        "model": details.get("global_model"),
        "distortion": details.get("distortion"),
        "scale_px": details.get("scale_px", 1.0),
        "test": details.get("test", ""),
        "p_text": "not computed" if p is None else f"{p:.3g}",
        "alpha": details.get("alpha"),
        "decision": decision,
        "region_text": _region_text(details.get("region")),
        "lines": _line_rows(details.get("lines", [])),
        "rules": details["paper_rules"],
        "references": list(REFERENCES),
    }
    figures = {
        "overlay": Figure(overlay_png(evidence.pixels, details), "image/png",
                          "Extracted lines, numbered as in the table: red departs from the lens model, orange |z| ≥ 2, "
                          "green consistent, blue not informative."),
    }
    if details.get("lines"):
        figures["k1_plot"] = Figure(k1_plot_svg(details), "image/svg+xml",
                                    "k1 of each line against its signed distance from the image centre, with one "
                                    "standard error (filled: joint estimator; hollow: the paper's estimator).")
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Lens radial distortion", template=template, context=context, figures=figures)
