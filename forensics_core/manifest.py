"""``manifest.json``: the SHA-256 of every file of a report bundle and of the evidence.

The manifest is signed by a detached CMS signature, ``manifest.json.p7s``,
so that one check with a standard tool covers the whole folder::

    openssl cms -verify -binary -inform DER -in manifest.json.p7s \\
        -content manifest.json -CAfile signer.pem -out /dev/null
    sha256sum -c <(jq -r '.files[] | "\\(.sha256)  \\(.name)"' manifest.json)
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from .findings import EvidenceInfo, Tool

FINDINGS_NAME = "findings.json"
MANIFEST_NAME = "manifest.json"
SIGNATURE_NAME = "manifest.json.p7s"
SIGNER_CERT_NAME = "signer.pem"
HTML_NAME = "report.html"
PDF_NAME = "report.pdf"
MANIFEST_VERSION = "1"


def sha256_file(path: Path) -> str:
    """SHA-256 of a file, read in chunks."""
    digest = hashlib.sha256()
    with path.open("rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


@dataclass(frozen=True)
class FileEntry:
    """One file of the bundle, named relative to the bundle folder."""

    name: str
    size: int
    sha256: str


@dataclass(frozen=True)
class Manifest:
    """What ``manifest.json`` records.

    Attributes
    ----------
    tool : Tool
    created : str
        ISO 8601 UTC time the manifest was made.
    case_id, exhibit_id : str or None
    evidence : dict
        Name, size, SHA-256 and SHA-512 of the evidence and when they were taken.
    signer : dict
        Subject, SHA-256 fingerprint and self-signed flag of the signing certificate.
    files : list of FileEntry
    outputs : list of str or None
        The documents the run was asked to produce (``findings.json``, the
        report's HTML and PDF, ``signer.pem``); ``verify`` fails a bundle
        whose manifest does not list one of them. None in manifests written
        before this field existed.
    """

    tool: Tool
    created: str
    case_id: str | None
    exhibit_id: str | None
    evidence: dict[str, Any]
    signer: dict[str, Any]
    files: list[FileEntry]
    outputs: list[str] | None = None

    def to_bytes(self) -> bytes:
        doc = {"manifest_version": MANIFEST_VERSION, **asdict(self)}
        return (json.dumps(doc, indent=2, ensure_ascii=False, sort_keys=False) + "\n").encode("utf-8")

    @classmethod
    def from_bytes(cls, data: bytes) -> Manifest:
        """Parse ``manifest.json``.

        Raises
        ------
        ValueError
            When it is not a manifest of a version this tool reads.
        """
        try:
            doc = json.loads(data.decode("utf-8"))
        except RecursionError:
            raise ValueError("manifest is nested too deeply to be a forensics manifest") from None
        if not isinstance(doc, dict) or doc.get("manifest_version") != MANIFEST_VERSION:
            raise ValueError("not a forensics manifest of version " + MANIFEST_VERSION)
        try:
            return cls(
                tool=Tool(**doc["tool"]),
                created=str(doc["created"]),
                case_id=doc.get("case_id"),
                exhibit_id=doc.get("exhibit_id"),
                evidence=dict(doc["evidence"]),
                signer=dict(doc["signer"]),
                files=[FileEntry(str(f["name"]), int(f["size"]), str(f["sha256"])) for f in doc["files"]],
                outputs=None if doc.get("outputs") is None else [str(n) for n in doc["outputs"]],
            )
        except (KeyError, TypeError) as exc:
            raise ValueError(f"manifest is missing or mangles a field: {exc}") from None


def evidence_entry(info: EvidenceInfo) -> dict[str, Any]:
    return {"name": info.name, "size": info.size, "sha256": info.sha256, "sha512": info.sha512,
            "hashed_at": info.hashed_at}


def file_entries(folder: Path, names: list[str]) -> list[FileEntry]:
    """Hash the named files of ``folder`` (sorted by name, so manifests compare line by line)."""
    return [FileEntry(n, (folder / n).stat().st_size, sha256_file(folder / n)) for n in sorted(set(names))]
