"""The lens distortion section of the evidence report."""

from __future__ import annotations

from importlib.resources import files
from typing import Any

from forensics_core import DetectorFinding, Evidence, Status
from forensics_core.report import Figure, ReportSection, Table

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


def _status(line: dict[str, Any]) -> str:
    return "departs alone: curved or non-straight object?" if line.get("outlier") else _STATUS_WORDS[line_class(line)]


def _line_rows(lines: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The lines the page shows: those the test flagged or that depart on their own."""
    rows = []
    for ln in lines:
        if not (ln.get("flagged") or ln.get("outlier")):
            continue
        rows.append({
            "id": ln["id"], "distance": ln["distance"], "length_px": ln["length_px"],
            "k1_text": _num(ln["k1"], "+.4f"), "se_text": _num(ln["k1_stderr"], ".4f"),
            "z_text": _num(ln["z"], "+.1f"), "css": f"line-{line_class(ln)}", "status": _status(ln),
        })
    return rows


LINE_COLUMNS = ["line", "distance", "length_px", "n_points", "pieces", "k1_joint", "k1_stderr", "k1_stderr_noise",
                "k1_paper", "residual_rms_px", "k1_model", "delta_k1", "delta_k1_stderr", "z", "informative",
                "flagged", "outlier", "status", "breaks_rule_a", "breaks_rule_b", "x0_px", "y0_px", "x1_px",
                "y1_px"]


def lines_table(details: dict[str, Any]) -> Table:
    """Every extracted line as the paper's Table 2 lists them, with what the test made of it.

    The points of each line stay in ``findings.json`` (``details.lines[].points_px``).
    """
    rules = details.get("paper_rules") or {}
    broken = {key: set(rules.get(key, {}).get("violating_line_ids", [])) for key in ("a", "b")}
    rows = []
    for ln in details.get("lines", []):
        (x0, y0), (x1, y1) = ln["endpoints_px"]
        rows.append([ln["id"], ln["distance"], ln["length_px"], ln["n_points"], ln["pieces"], ln["k1"],
                     ln["k1_stderr"], ln.get("k1_stderr_noise"), ln["k1_paper"], ln["residual_rms_px"],
                     ln.get("k1_model"), ln.get("delta_k1"), ln.get("delta_k1_stderr"), ln["z"],
                     ln.get("informative", True), bool(ln.get("flagged")), bool(ln.get("outlier")), _status(ln),
                     ln["id"] in broken["a"], ln["id"] in broken["b"], x0, y0, x1, y1])
    return Table(LINE_COLUMNS, rows, "every extracted line: distance, length, k1 by both estimators with its "
                                     "standard error, residual, z against the model, status and the paper's rules")


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
    """The section for one lens distortion finding: figures, the lens, the test, method and limitations.

    Every line's row goes to ``lens_distortion-lines.csv`` beside the report;
    the page lists only the lines that depart.
    """
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
        "departing": _line_rows(details.get("lines", [])),
        "n_lines": len(details.get("lines", [])),
        "n_informative": sum(bool(ln.get("informative", True)) for ln in details.get("lines", [])),
        "n_strong": sum(line_class(ln) == "strong" for ln in details.get("lines", [])),
        "rules": details["paper_rules"],
        "references": list(REFERENCES),
    }
    figures = {
        "overlay": Figure(overlay_png(evidence.pixels, details), "image/png",
                          "Extracted lines, numbered as in the lines table (CSV): red departs from the lens model, "
                          "orange |z| ≥ 2, green consistent, blue not informative."),
    }
    if details.get("lines"):
        figures["k1_plot"] = Figure(k1_plot_svg(details), "image/svg+xml",
                                    "k1 of each line against its signed distance from the image centre, with one "
                                    "standard error (filled: joint estimator; hollow: the paper's estimator).")
    tables = {"lines": lines_table(details)} if details.get("lines") else {}
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Lens radial distortion", template=template, context=context, figures=figures,
                         tables=tables)
