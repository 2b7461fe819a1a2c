"""The dq section of the evidence report."""

from __future__ import annotations

from importlib.resources import files
from typing import Any

from forensics_core import DetectorFinding, Evidence
from forensics_core.report import Figure, ReportSection, Table

from .figures import votes_png
from .spec import REFERENCES
from .votes import decode_votes

SHOWN_WINDOWS = 3
"""Windows listed on the page, the most significant first; all those listed in the finding are in the CSV file."""


def _tables(d: dict[str, Any]) -> dict[str, Table]:
    """Every frequency's earlier step and every window lacking the earlier quantisation, in pixels."""
    tables = {"frequencies": Table(
        ["row", "col", "stored_step", "earlier_step", "share_double", "gain_nats", "used"],
        [[r["row"], r["col"], r["q2"], r["q1"], r["alpha"], r["gain_nats"], r["used"]] for r in d["frequencies"]],
        "each AC frequency's stored and earlier quantisation step")}
    if d.get("windows"):
        tables["windows"] = Table(
            ["x_px", "y_px", "side_px", "informative_blocks", "voting_single", "photo_rate", "log10_nfa"],
            [[8 * w["col"], 8 * w["row"], 8 * w["size"], w["n"], w["k"], w["expected"], w["log10_nfa"]]
             for w in d["windows"]],
            "the windows lacking the earlier quantisation (NFA below 1)")
    return tables


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one dq finding: the vote map, the primary steps, the windows, the method and its limits.

    Every frequency and every window go to CSV files beside the report; the
    page lists the frequencies used and the first windows.
    """
    d = finding.details
    figures = {}
    if d.get("block_votes"):
        informative, single = decode_votes(d["block_votes"])
        figures["votes"] = Figure(
            votes_png(evidence.luma, informative, single, d), "image/png",
            "Each 8 × 8 block's vote: green, its coefficients carry the earlier quantisation; red, they do not; "
            "untinted, undecided, clipped or at the edge. Yellow, windows with NFA below 1.")
    frequencies = d.get("frequencies", [])
    context = {"used": [r for r in frequencies if r["used"]], "n_frequencies": len(frequencies),
               "windows": d.get("windows", [])[:SHOWN_WINDOWS], "n_windows": len(d.get("windows", [])),
               "best": d.get("best"), "params": finding.parameters, "log10_lr": finding.log10_lr,
               "references": list(REFERENCES), "d": d}
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Double JPEG compression (aligned)", template=template, context=context,
                         figures=figures, tables=_tables(d))
