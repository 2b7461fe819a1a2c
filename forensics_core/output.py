"""Where and how outputs are written: per-photo folders, atomic writes, and
the per-photo unit of work that ``analyze`` and ``batch`` share."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from .analysis import Options, analyze_evidence
from .evidence import Evidence, load_evidence
from .findings import Findings
from .plugins import PluginHost, one_line

if TYPE_CHECKING:
    from .report.render import ReportOptions
    from .signing import ExaminerKey

FINDINGS_NAME = "findings.json"


def output_dir_for(out_dir: Path, photo: Path, sha256: str, used: set[str]) -> Path:
    """``out_dir/<photo stem>``, or ``<stem>-<first 12 hex of sha256>`` when the stem is taken in this run."""
    stem = photo.stem or "photo"
    name = stem if stem not in used else f"{stem}-{sha256[:12]}"
    used.add(name)
    return out_dir / name


def write_atomic(path: Path, data: bytes) -> Path:
    """Write ``data`` to a temporary file beside ``path``, then rename it into place.

    A run stopped at any moment leaves either the old file or the new one,
    never half of one.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_findings(findings: Findings, folder: Path) -> Path:
    return write_atomic(folder / FINDINGS_NAME, findings.to_json().encode("utf-8"))


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
    """One photo analysed and written: its findings, folder and the URLs the PDF renderer refused."""

    findings: Findings
    folder: Path
    findings_path: Path
    refused_urls: list[str] = field(default_factory=list)


def write_report(findings: Findings, evidence: Evidence, folder: Path, host: PluginHost,
                 report: ReportSettings) -> list[str]:
    """Write the signed report bundle beside ``findings.json``; return the URLs the PDF renderer refused.

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
                              options=report.options, organisation=report.organisation, tsa_url=report.tsa_url)
    except OSError:
        raise
    except Exception as exc:  # rendering or signing failed for this photo; the others go on
        if os.environ.get("FORENSICS_DEBUG"):
            raise
        raise ReportError(one_line(exc)) from None
    return list(result.refused_urls)


def examine_photo(photo: Path, folder_for: Callable[[Evidence], Path], host: PluginHost, options: Options,
                  report: ReportSettings | None = None) -> Examined:
    """Take in ``photo``, run the detectors and write ``findings.json`` (and the report) into its folder.

    Parameters
    ----------
    photo : Path
        The evidence file (read, never written).
    folder_for : callable
        Gives the output folder once the evidence is loaded (its hash may
        choose the name); it may raise to refuse the evidence.
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
    evidence = load_evidence(photo, max_pixels=options.max_pixels)
    findings = analyze_evidence(evidence, host, options)
    folder = folder_for(evidence)
    path = write_findings(findings, folder)
    refused = write_report(findings, evidence, folder, host, report) if report is not None else []
    return Examined(findings, folder, path, refused)
