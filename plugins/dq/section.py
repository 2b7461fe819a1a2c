"""The dq section of the evidence report."""

from __future__ import annotations

from importlib.resources import files

from forensics_core import DetectorFinding, Evidence
from forensics_core.report import Figure, ReportSection

from .figures import votes_png
from .spec import REFERENCES
from .votes import decode_votes


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one dq finding: the vote map, the primary steps, the windows, the method and its limits."""
    d = finding.details
    figures = {}
    if d.get("block_votes"):
        informative, single = decode_votes(d["block_votes"])
        figures["votes"] = Figure(
            votes_png(evidence.luma, informative, single, d), "image/png",
            "Each 8 × 8 block's vote: green, its coefficients carry the earlier quantisation; red, they do not; "
            "untinted, undecided, clipped or at the edge. Yellow, windows with NFA below 1.")
    context = {"frequencies": d.get("frequencies", []), "windows": d.get("windows", []), "best": d.get("best"),
               "params": finding.parameters, "log10_lr": finding.log10_lr, "references": list(REFERENCES),
               "d": d}
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Double JPEG compression (aligned)", template=template, context=context,
                         figures=figures)
