"""The provenance section of the evidence report."""

from __future__ import annotations

from importlib.resources import files
from typing import Any

from forensics_core import DetectorFinding, Evidence
from forensics_core.report import ReportSection, Table

from .spec import REFERENCES

SHOWN_ROWS = 5
"""Actions and ingredients listed on the page; all of them are in the CSV files."""


def _tables(cred: dict[str, Any], edits: list[str]) -> dict[str, Table]:
    """Every declared action and every ingredient of the manifest, as the SDK read them."""
    tables = {}
    if cred.get("actions"):
        tables["actions"] = Table(
            ["action", "software", "when", "source_type", "edit"],
            [[a.get("action"), a.get("softwareAgent"), a.get("when"), a.get("digitalSourceType"),
              a.get("action") in edits] for a in cred["actions"]],
            "every action the manifest declares")
    if cred.get("ingredients"):
        tables["ingredients"] = Table(
            ["title", "relationship", "format"],
            [[i.get("title"), i.get("relationship"), i.get("format")] for i in cred["ingredients"]],
            "every ingredient the manifest names")
    return tables


def absent_section(finding: DetectorFinding) -> ReportSection:
    """The short section for a file that carries no readable Content Credentials: where they were looked for."""
    d = finding.details
    context = {"c2pa": d.get("c2pa"), "references": list(REFERENCES),
               "sidecar": d.get("sidecar_sha256") is not None or "sidecar_error" in d}
    template = files(__package__).joinpath("templates/absent.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Content Credentials (C2PA)", template=template, context=context)


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one provenance finding: validation, signer, actions, ingredients, and what it proves.

    Every action and ingredient goes to CSV files beside the report; the page lists the first few.
    """
    d = finding.details
    cred, edits = d["credentials"], d.get("edits", [])
    context = {"cred": cred, "edits": edits, "c2pa": d.get("c2pa"),
               "actions": (cred.get("actions") or [])[:SHOWN_ROWS],
               "ingredients": (cred.get("ingredients") or [])[:SHOWN_ROWS],
               "sidecar_sha256": d.get("sidecar_sha256"), "references": list(REFERENCES),
               "trust": bool(finding.parameters.get("trust_anchors_file")),
               "anchors_sha256": d.get("trust_anchors_sha256"), "sidecar_error": d.get("sidecar_error"),
               "sidecar_cred": d.get("sidecar_credentials")}
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Content Credentials (C2PA)", template=template, context=context,
                         tables=_tables(cred, edits))
