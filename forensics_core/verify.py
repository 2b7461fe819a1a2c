"""Check a report bundle: signatures intact, every file as signed, the evidence as recorded.

A bundle passes only when all of these hold:

* ``manifest.json.p7s`` is a valid CMS signature over ``manifest.json``;
* every file the manifest lists is present with its SHA-256, and the folder
  holds no file the manifest does not list;
* ``report.pdf`` (when listed) carries one signature, pyHanko's
  ``bottom_line`` is true, DocMDP is respected and the signature covers the
  ENTIRE file (bytes appended after ``%%EOF`` fail);
* the PDF and the manifest are signed by the certificate the manifest names;
* the evidence, when given, has the SHA-256 and SHA-512 the manifest records.

Trust. With ``--trust CERT`` both signatures must chain to that certificate.
Without it, the signer's own certificate (carried in the signature) is taken
as the anchor: that proves the files are unchanged since signing, not who
signed them, and the result says so.
"""

from __future__ import annotations

import asyncio
import hashlib
import stat
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path

from asn1crypto import cms
from asn1crypto import x509 as asn1_x509

from .manifest import MANIFEST_NAME, PDF_NAME, SIGNATURE_NAME, Manifest, sha256_file


@dataclass(frozen=True)
class Problem:
    """One failed check: the file (or "evidence") and why, in one line."""

    subject: str
    reason: str

    def __str__(self) -> str:
        return f"{self.subject}: {self.reason}"


@dataclass
class Verification:
    """The outcome of :func:`verify_bundle`."""

    problems: list[Problem] = field(default_factory=list)
    passed: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems

    def fail(self, subject: str, reason: str) -> None:
        self.problems.append(Problem(subject, reason))


def _fingerprint(cert: asn1_x509.Certificate) -> str:
    digest = hashlib.sha256(cert.dump()).hexdigest().upper()
    return ":".join(digest[i : i + 2] for i in range(0, len(digest), 2))


def load_trust(path: Path) -> list[asn1_x509.Certificate]:
    """Certificates from a PEM (one or more) or DER file.

    Raises
    ------
    ValueError
        When the file holds no certificate.
    """
    from pyhanko.keys import load_certs_from_pemder

    try:
        certs = list(load_certs_from_pemder([str(path)]))
    except (OSError, ValueError) as exc:
        raise ValueError(f"cannot read trusted certificate {path}: {exc}") from None
    if not certs:
        raise ValueError(f"{path} holds no certificate")
    return certs


def _context(roots: list[asn1_x509.Certificate]):
    from pyhanko_certvalidator import ValidationContext

    # Offline by design: a verification must give the same answer without a network.
    return ValidationContext(trust_roots=roots, allow_fetching=False, revocation_mode="soft-fail")


def _check_manifest_signature(folder: Path, manifest_bytes: bytes, trust: list[asn1_x509.Certificate] | None,
                              result: Verification) -> asn1_x509.Certificate | None:
    """Validate the detached CMS signature; return the signer's certificate when it is valid."""
    from pyhanko.sign.validation.generic_cms import async_validate_detached_cms

    try:
        info = cms.ContentInfo.load((folder / SIGNATURE_NAME).read_bytes())
        signed = info["content"]
        signer_info = signed["signer_infos"][0]
        sid = signer_info["sid"]
        certs = [c.chosen for c in signed["certificates"] if c.name == "certificate"]
        signer = next(c for c in certs if sid.name == "issuer_and_serial_number"
                      and c.issuer == sid.chosen["issuer"] and c.serial_number == sid.chosen["serial_number"].native)
        status = asyncio.run(async_validate_detached_cms(manifest_bytes, signed,
                                                         signer_validation_context=_context(trust or [signer])))
    except FileNotFoundError:
        result.fail(SIGNATURE_NAME, "missing")
        return None
    except Exception as exc:  # any parse failure of a damaged signature file is a failed check
        result.fail(SIGNATURE_NAME, f"not a readable CMS signature ({type(exc).__name__})")
        return None
    if not status.intact:
        result.fail(MANIFEST_NAME, "does not match its signature manifest.json.p7s (altered)")
        return None
    if not status.valid:
        result.fail(SIGNATURE_NAME, "signature is not valid")
        return None
    if not status.bottom_line:
        result.fail(SIGNATURE_NAME, "signer certificate is not trusted" + (" by --trust" if trust else ""))
        return None
    result.passed.append(f"{SIGNATURE_NAME}: valid CMS signature over {MANIFEST_NAME} by {signer.subject.human_friendly}")
    return signer


def _check_pdf(path: Path, trust: list[asn1_x509.Certificate] | None, signer: asn1_x509.Certificate | None,
               result: Verification) -> None:
    from pyhanko.pdf_utils.reader import PdfFileReader
    from pyhanko.sign.validation import validate_pdf_signature
    from pyhanko.sign.validation.status import SignatureCoverageLevel

    name = path.name
    try:
        reader = PdfFileReader(BytesIO(path.read_bytes()))
        signatures = reader.embedded_signatures
        if len(signatures) != 1:
            result.fail(name, f"expected one signature, found {len(signatures)}")
            return
        sig = signatures[0]
        roots = trust or [sig.signer_cert]
        status = validate_pdf_signature(sig, _context(roots))
    except Exception as exc:  # a damaged PDF may fail to parse anywhere; that is a failed check
        result.fail(name, f"signature cannot be checked: the file is damaged ({type(exc).__name__})")
        return
    if not status.intact or not status.valid:
        result.fail(name, "PDF signature is broken (the signed bytes were altered)")
    elif status.coverage is not SignatureCoverageLevel.ENTIRE_FILE:
        result.fail(name, f"PDF signature does not cover the entire file (coverage {status.coverage.name}; "
                          "bytes were added after signing)")
    elif status.docmdp_ok is False:
        result.fail(name, "changes after the certification signature violate its DocMDP permissions")
    elif not status.bottom_line:
        result.fail(name, "PDF signer certificate is not trusted" + (" by --trust" if trust else ""))
    elif signer is not None and _fingerprint(sig.signer_cert) != _fingerprint(signer):
        result.fail(name, "signed by a different certificate than the manifest")
    else:
        result.passed.append(f"{name}: certification signature valid, covers the entire file")


def _check_files(folder: Path, manifest: Manifest, result: Verification) -> None:
    listed = {f.name for f in manifest.files}
    for entry in manifest.files:
        path = folder / entry.name
        if Path(entry.name).is_absolute() or ".." in Path(entry.name).parts:
            result.fail(entry.name, "manifest names a file outside the bundle")
        elif not path.is_file():
            result.fail(entry.name, "missing")
        elif sha256_file(path) != entry.sha256:
            result.fail(entry.name, "SHA-256 does not match the manifest (altered)")
        else:
            result.passed.append(f"{entry.name}: SHA-256 matches")
    for path in sorted(folder.iterdir()):
        if path.name not in listed and path.name not in (MANIFEST_NAME, SIGNATURE_NAME):
            result.fail(path.name, "not listed in the manifest")


def _check_evidence(evidence: Path, manifest: Manifest, result: Verification) -> None:
    """Hash the evidence in chunks, after checking it is a regular file of the recorded size.

    A FIFO would block the read and a device such as ``/dev/zero`` never
    ends; neither can be the evidence, so both are refused before reading.
    """
    recorded = manifest.evidence
    try:
        st = evidence.stat()
    except OSError as exc:
        result.fail("evidence", f"cannot read {evidence}: {exc.strerror or exc}")
        return
    if not stat.S_ISREG(st.st_mode):
        result.fail("evidence", f"{evidence} is not a regular file")
        return
    if recorded.get("size") is not None and st.st_size != recorded["size"]:
        result.fail("evidence", f"{evidence.name} has {st.st_size:,} bytes, not the {recorded['size']:,} recorded "
                                f"for {recorded.get('name')}")
        return
    sha256, sha512 = hashlib.sha256(), hashlib.sha512()
    try:
        with evidence.open("rb") as f:
            for chunk in iter(lambda: f.read(1 << 20), b""):
                sha256.update(chunk)
                sha512.update(chunk)
    except OSError as exc:
        result.fail("evidence", f"cannot read {evidence}: {exc.strerror or exc}")
        return
    if sha256.hexdigest() != recorded.get("sha256") or sha512.hexdigest() != recorded.get("sha512"):
        result.fail("evidence", f"{evidence.name} does not match the SHA-256/SHA-512 recorded for {recorded.get('name')}")
    else:
        result.passed.append(f"evidence: {evidence.name} matches SHA-256 and SHA-512")


def verify_bundle(folder: Path, evidence: Path | None = None, trust: Path | None = None) -> Verification:
    """Run every check on the bundle in ``folder``; see the module docstring.

    Raises
    ------
    ValueError
        When ``trust`` cannot be read (a usage error, not a failed check).
    """
    result = Verification()
    roots = load_trust(trust) if trust is not None else None
    try:
        manifest_bytes = (folder / MANIFEST_NAME).read_bytes()
    except OSError:
        result.fail(MANIFEST_NAME, "missing")
        return result
    signer = _check_manifest_signature(folder, manifest_bytes, roots, result)
    if signer is None:
        # An unauthenticated manifest says nothing about the other files; the
        # PDF's own signature can still be checked.
        if (folder / PDF_NAME).is_file():
            _check_pdf(folder / PDF_NAME, roots, None, result)
        result.notes.append("files not compared with the manifest, whose signature failed")
        return result
    try:
        manifest = Manifest.from_bytes(manifest_bytes)
    except (ValueError, UnicodeDecodeError) as exc:
        result.fail(MANIFEST_NAME, f"unreadable: {exc}")
        return result
    if manifest.signer.get("sha256_fingerprint") != _fingerprint(signer):
        result.fail(MANIFEST_NAME, "names a different signing certificate than the one that signed it")
    _check_files(folder, manifest, result)
    if any(f.name == PDF_NAME for f in manifest.files) and (folder / PDF_NAME).is_file():
        _check_pdf(folder / PDF_NAME, roots, signer, result)
    if evidence is not None:
        _check_evidence(evidence, manifest, result)
    if roots is None:
        result.notes.append("signer identity not checked: no --trust certificate given, so the signatures prove the "
                            "files are unchanged since signing, not who signed them")
    if manifest.signer.get("self_signed"):
        result.notes.append(f"the signing certificate is self-signed ({manifest.signer.get('subject')}, "
                            f"SHA-256 {manifest.signer.get('sha256_fingerprint')})")
    return result
