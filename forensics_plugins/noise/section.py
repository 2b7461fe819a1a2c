"""The noise section of the evidence report."""

from __future__ import annotations

from importlib.resources import files
from typing import Any

from forensics_core import DetectorFinding, Evidence
from forensics_core.report import Figure, ReportSection, Table

from .detector import decode_z
from .figures import z_map_png
from .spec import REFERENCES

SHOWN_WINDOWS = 3
"""Departing windows listed on the page; all those listed in the finding are in the CSV file."""


def windows_table(d: dict[str, Any]) -> Table | None:
    """The departing windows in pixels, the most departing first; None when none departs."""
    if not d.get("windows"):
        return None
    return Table(["x_px", "y_px", "side_px", "blocks_compared", "mean_z", "departure", "noise"],
                 [[8 * w["col"], 8 * w["row"], 8 * w["size"], w["n"], w["mean_z"], w["deviation"],
                   "noisier" if w["deviation"] > 0 else "smoother"] for w in d["windows"]],
                 "the windows departing by the listing threshold or more")


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one noise finding: the map, the departing windows, the method and its limits.

    The departing windows go to ``noise-windows.csv`` beside the report; the page lists the first few.
    """
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
    table = windows_table(d)
    best, listed = d.get("best"), d.get("windows", [])
    shown = ([best] if best else []) + [w for w in listed if w != best]
    context = {"shown": shown[:SHOWN_WINDOWS], "n_windows": len(listed), "params": finding.parameters,
               "log10_lr": finding.log10_lr, "references": list(REFERENCES), "d": d}
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Noise-level inconsistency", template=template, context=context, figures=figures,
                         tables={"windows": table} if table else {})
