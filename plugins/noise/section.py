"""The noise section of the evidence report."""

from __future__ import annotations

from importlib.resources import files

from forensics_core import DetectorFinding, Evidence
from forensics_core.report import Figure, ReportSection

from .detector import decode_z
from .figures import z_map_png
from .spec import REFERENCES


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one noise finding: the map, the departing windows, the method and its limits."""
    d = finding.details
    figures = {}
    if d.get("z_map"):
        z, used = decode_z(d["z_map"])
        figures["map"] = Figure(
            z_map_png(evidence.luma, z, used, d), "image/png",
            "Fine-grain noise against content of like grey level and texture elsewhere in the photo, averaged over "
            "32 × 32 pixels: red, noisier; blue, smoother; untinted, as expected or not compared (clipped, or too "
            "few like blocks). White, the window departing most; yellow, windows departing by "
            f"{finding.parameters.get('list_threshold')} or more.")
    context = {"windows": d.get("windows", []), "best": d.get("best"), "params": finding.parameters,
               "log10_lr": finding.log10_lr, "references": list(REFERENCES), "d": d}
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Noise-level inconsistency", template=template, context=context, figures=figures)
