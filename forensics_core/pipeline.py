"""The per-photo unit of work that ``analyze`` and ``batch`` share: take in, analyse, write findings and report."""

from __future__ import annotations

import hashlib
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from . import stopping
from .analysis import Options, analyze_evidence
from .evidence import Evidence, load_evidence
from .findings import Findings
from .manifest import FINDINGS_NAME, HTML_NAME, MANIFEST_NAME, PDF_NAME
from .output import Placement, publish, staging_folder, write_findings
from .plugins import PluginHost, one_line

if TYPE_CHECKING:
    from .report.layout_process import LayoutProcess
    from .report.render import ReportOptions
    from .signing import ExaminerKey


class ReportError(Exception):
    """The report of one photo could not be made; the message is one line."""


@dataclass(frozen=True)
class ReportSettings:
    """How the signed report of each photo is made.

    Attributes
    ----------
    key : ExaminerKey
        Signs the PDF and the manifest.
    formats : tuple of {"html", "pdf"}
    options : ReportOptions
        Exhibit id and paper size.
    organisation, tsa_url : str or None
        Signature block organisation; RFC 3161 time-stamping service.
    """

    key: ExaminerKey
    formats: tuple[str, ...]
    options: ReportOptions
    organisation: str | None = None
    tsa_url: str | None = None


@dataclass
class Examined:
    """One photo analysed and written (or ``kept``: its outputs were already there): findings, folder, refused URLs."""

    findings: Findings
    folder: Path
    findings_path: Path
    refused_urls: list[str] = field(default_factory=list)
    kept: bool = False


def expected_files(report: ReportSettings | None) -> set[str]:
    """The names a run writes into each photo's folder."""
    if report is None:
        return {FINDINGS_NAME}
    return {FINDINGS_NAME, MANIFEST_NAME} | {HTML_NAME for f in report.formats if f == "html"} | \
        {PDF_NAME for f in report.formats if f == "pdf"}


def write_report(findings: Findings, evidence: Evidence, folder: Path, host: PluginHost,
                 report: ReportSettings, layout: LayoutProcess | None = None) -> list[str]:
    """Write the signed report bundle beside ``findings.json``; return the URLs the PDF renderer refused.

    ``layout`` lays out the PDF, warm (:func:`started_layout`); without it the PDF is laid out here.

    Raises
    ------
    OSError
        When a file cannot be written (the caller says "cannot write output").
    ReportError
        When rendering or signing failed for this photo.
    """
    from .report.bundle import write_bundle

    try:
        result = write_bundle(findings, evidence, folder, report.key, formats=report.formats, host=host,
                              options=report.options, organisation=report.organisation, tsa_url=report.tsa_url,
                              layout=layout)
    except OSError:
        raise
    except Exception as exc:  # rendering or signing failed for this photo; the others go on
        if os.environ.get("FORENSICS_DEBUG"):
            raise
        raise ReportError(one_line(exc)) from None
    return list(result.refused_urls)


def started_layout(report: ReportSettings | None) -> LayoutProcess | None:
    """The process that will lay out the PDF, started now so that it is warm when the report is ready.

    None when no PDF is asked for or the platform cannot fork (the PDF is then laid out in this process).
    """
    if report is None or "pdf" not in report.formats:
        return None
    from .report.layout_process import started

    return started()


def _changed_since(photo: Path, sha256: str) -> str | None:
    """Why the file on disk is no longer the hashed evidence, or None when it still is."""
    digest = hashlib.sha256()
    try:
        with photo.open("rb") as fh:
            for chunk in iter(lambda: fh.read(1 << 20), b""):
                digest.update(chunk)
    except OSError as exc:
        return f"the file could not be read again after the analysis: {exc.strerror or exc}"
    if digest.hexdigest() != sha256:
        return (f"the file changed during the analysis (its SHA-256 is now {digest.hexdigest()}): a plugin or another "
                f"program wrote to it; these findings are of the bytes as first hashed")
    return None


def examine_photo(photo: Path, place: Callable[[Evidence, Findings], Placement], host: PluginHost, options: Options,
                  report: ReportSettings | None = None) -> Examined:
    """Take in ``photo``, run the detectors and write ``findings.json`` (and the report) into its folder.

    Parameters
    ----------
    photo : Path
        The evidence file (read, never written).
    place : callable
        Gives the :class:`Placement` once the evidence is loaded and analysed
        (its hash and the findings' parameters may choose it); it may raise
        to refuse the evidence.
    host : PluginHost
    options : Options
    report : ReportSettings, optional
        Without it only ``findings.json`` is written.

    Raises
    ------
    EvidenceError
        When the photo cannot be taken in.
    OSError
        When an output cannot be written.
    ReportError
        When the report cannot be made.
    """
    layout = started_layout(report)
    evidence = load_evidence(photo, max_pixels=options.max_pixels)
    findings = analyze_evidence(evidence, host, options)
    findings.evidence.changed_during_analysis = _changed_since(photo, evidence.info.sha256)
    stopping.check()
    placement = place(evidence, findings)
    if placement.action == "kept":
        return Examined(findings, placement.folder, placement.folder / FINDINGS_NAME, kept=True)
    # The bundle is made whole beside its folder, then renamed into place, so
    # an interruption leaves the folder as it was, never half a bundle or a
    # mixture of two.
    with staging_folder(placement.folder) as staging:
        try:
            write_findings(findings, staging)
            refused = write_report(findings, evidence, staging, host, report, layout) if report is not None else []
            stopping.check()
            placement = publish(staging, placement, lambda: place(evidence, findings))
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
        if placement.action == "kept":
            shutil.rmtree(staging, ignore_errors=True)
    if placement.action == "kept":
        return Examined(findings, placement.folder, placement.folder / FINDINGS_NAME, kept=True)
    return Examined(findings, placement.folder, placement.folder / FINDINGS_NAME, refused)
