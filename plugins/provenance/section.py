"""The provenance section of the evidence report."""

from __future__ import annotations

from importlib.resources import files

from forensics_core import DetectorFinding, Evidence
from forensics_core.report import ReportSection

from .spec import REFERENCES


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one provenance finding: validation, signer, actions, ingredients, and what it proves."""
    d = finding.details
    context = {"cred": d["credentials"], "edits": d.get("edits", []), "c2pa": d.get("c2pa"),
               "sidecar_sha256": d.get("sidecar_sha256"), "references": list(REFERENCES),
               "trust": bool(finding.parameters.get("trust_anchors_file")),
               "anchors_sha256": d.get("trust_anchors_sha256"), "sidecar_error": d.get("sidecar_error"),
               "sidecar_cred": d.get("sidecar_credentials")}
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Content Credentials (C2PA)", template=template, context=context)
