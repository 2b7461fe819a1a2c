"""The prnu section of the evidence report: references, the source test, the local map, method and limits."""

from __future__ import annotations

from importlib.resources import files

from forensics_core import DetectorFinding, Evidence
from forensics_core.report import Figure, ReportSection, Table

from .figures import local_map_png
from .spec import REFERENCES


def section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one prnu finding; the reference photos' hashes go to ``prnu-references.csv`` as well."""
    d = finding.details
    ref = d.get("reference") or {}
    figures = {}
    local = d.get("local")
    if local and local.get("grid"):
        figures["map"] = Figure(
            local_map_png(evidence.luma, local), "image/png",
            f"Blocks of {local['block']} px every {local['step']} px: red where the block's correlation with the "
            "fingerprint is nearer 0 than its content predicts (no fingerprint), green where it is near the "
            "prediction, untinted where the content cannot decide (dark, clipped or busy). Yellow: flagged regions.")
    tables = {}
    if ref.get("files"):
        tables["references"] = Table(["name", "sha256"], [[f["name"], f["sha256"]] for f in ref["files"]],
                                     "the reference photos and their SHA-256")
    calibration = d.get("calibration") or {}
    context = {"d": d, "ref": ref, "local": local, "params": finding.parameters, "log10_lr": finding.log10_lr,
               "source_lr": d.get("attribution_log10_lr"), "figures_data": calibration.get("source_figures") or {},
               "local_data": calibration.get("manipulation_figures") or {}, "calibration": calibration,
               "references": list(REFERENCES)}
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Sensor fingerprint (PRNU)", template=template, context=context, figures=figures,
                         tables=tables)
