"""Write a signed report bundle beside ``findings.json``.

The bundle is the folder an examiner hands over: ``findings.json``,
``report.html``, ``report.pdf`` (certified), the full-resolution figures,
``signer.pem``, ``manifest.json`` (SHA-256 of every file and of the
evidence) and ``manifest.json.p7s`` (its detached CMS signature). The
manifest is written last, so a bundle whose run was interrupted fails
verification instead of passing with missing pieces.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

from cryptography.hazmat.primitives import serialization

from ..evidence import Evidence
from ..findings import Findings
from ..manifest import (FINDINGS_NAME, HTML_NAME, MANIFEST_NAME, PDF_NAME, SIGNATURE_NAME, SIGNER_CERT_NAME, Manifest,
                        evidence_entry, file_entries)
from ..atomic import write_atomic
from ..plugins import PluginHost
from ..signing import UNNAMED_EXAMINER, ExaminerKey, sign_detached, sign_pdf
from ..text import visible
from .layout_process import LayoutProcess
from .render import ReportOptions, SignatureInfo, render_html, render_pdf

REPORT_FORMATS = ("html", "pdf")


@dataclass
class BundleResult:
    """What was written, and the URLs the PDF renderer refused to load (normally none)."""

    files: list[Path] = field(default_factory=list)
    refused_urls: list[str] = field(default_factory=list)


def _utc(moment: datetime) -> str:
    return moment.astimezone(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")


def signature_info(key: ExaminerKey, examiner: str | None, organisation: str | None) -> SignatureInfo:
    """The signature block's content; names not given fall back to the certificate's."""
    from cryptography.x509.oid import NameOID

    cn = key.cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    named = str(cn[0].value) if cn and str(cn[0].value) != UNNAMED_EXAMINER else None
    # A certificate made elsewhere may carry control or bidirectional characters in its names.
    return SignatureInfo(
        examiner=visible(examiner or named or ("not named: the signing key names no examiner (give --examiner, or "
                                               "make a key with forensics keys create)")),
        organisation=visible(organisation or key.organisation or "not given"),
        subject=visible(key.subject),
        fingerprint=key.fingerprint,
        self_signed=key.self_signed,
        valid_from=_utc(key.cert.not_valid_before_utc),
        valid_to=_utc(key.cert.not_valid_after_utc),
    )


def write_bundle(findings: Findings, evidence: Evidence, folder: Path, key: ExaminerKey, *,
                 formats: Collection[str] = REPORT_FORMATS, host: PluginHost | None = None,
                 options: ReportOptions | None = None, organisation: str | None = None,
                 tsa_url: str | None = None, layout: LayoutProcess | None = None) -> BundleResult:
    """Render, sign and write the report bundle into ``folder`` (which holds ``findings.json``).

    Parameters
    ----------
    findings, evidence
        The run and its evidence.
    folder : Path
        The photo's output folder; ``findings.json`` must already be there.
    key : ExaminerKey
        Signs the PDF and the manifest.
    formats : collection of {"html", "pdf"}
    host : PluginHost, optional
        Asked for the detectors' report sections.
    options : ReportOptions, optional
        Exhibit id, paper and report date (default: none, A4, now).
    organisation : str, optional
        Printed in the signature block; default the certificate's organisation.
    tsa_url : str, optional
        RFC 3161 time-stamping service for both signatures.
    layout : LayoutProcess, optional
        Lays out the PDF (:mod:`.layout_process`); without it the PDF is laid out here.
    """
    options = options or ReportOptions()
    report_date = options.report_date or _utc(datetime.now(timezone.utc))
    options = dataclasses.replace(options, report_date=report_date)
    info = signature_info(key, findings.parameters.get("examiner"), organisation)
    report = render_html(findings, evidence, info, options, host=host)
    result = BundleResult()
    names = [FINDINGS_NAME]

    def put(name: str, data: bytes) -> None:
        result.files.append(write_atomic(folder / name, data))
        names.append(name)

    for section in report.sections:
        for name, (data, _mime) in section.files.items():
            put(name, data)
    for name, data in report.files.items():
        put(name, data)
    if "html" in formats:
        put(HTML_NAME, report.html.encode("utf-8"))
    if "pdf" in formats:
        pdf = render_pdf(report, layout)
        location = organisation or key.organisation
        put(PDF_NAME, sign_pdf(pdf, key, reason="Forensic examination report; no changes permitted",
                               location=location, tsa_url=tsa_url))
    put(SIGNER_CERT_NAME, key.cert.public_bytes(serialization.Encoding.PEM))
    manifest = Manifest(
        tool=findings.tool, created=report_date, case_id=findings.parameters.get("case_id"),
        exhibit_id=options.exhibit_id, evidence=evidence_entry(findings.evidence),
        signer={"subject": key.subject, "sha256_fingerprint": key.fingerprint, "self_signed": key.self_signed},
        files=file_entries(folder, names),
        outputs=[FINDINGS_NAME] + [n for f, n in (("html", HTML_NAME), ("pdf", PDF_NAME)) if f in formats]
        + [SIGNER_CERT_NAME],
    ).to_bytes()
    result.files.append(write_atomic(folder / MANIFEST_NAME, manifest))
    result.files.append(write_atomic(folder / SIGNATURE_NAME, sign_detached(manifest, key, tsa_url=tsa_url)))
    result.refused_urls = report.refused_urls
    return result
