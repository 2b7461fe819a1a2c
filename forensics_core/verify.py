"""Check a report bundle: signatures intact, every file as signed, the evidence as recorded.

A bundle passes only when all of these hold:

* ``manifest.json.p7s`` is a valid CMS signature over ``manifest.json``;
* every file the manifest lists is present with its SHA-256, and the folder
  holds no file the manifest does not list;
* ``report.pdf`` (when listed) carries one signature, pyHanko's
  ``bottom_line`` is true, DocMDP is respected and the signature covers the
  ENTIRE file (bytes appended after ``%%EOF`` fail);
* the PDF and the manifest are signed by the certificate the manifest names;
* every document the manifest records as produced (``outputs``) is listed,
  and ``findings.json`` is about the evidence the manifest names;
* the signer chains to a trusted certificate: one of the trust store
  (:mod:`forensics_core.trust`) or one given with ``--trust`` for this run;
* the evidence, when given, has the SHA-256 and SHA-512 the manifest records.

Integrity and trust are checked apart. The signatures are first validated
against the signer's own certificate, which proves the files unchanged since
signing; a good signature by a signer nobody trusts then fails with
"signatures valid but signer not trusted", since anyone can make a key in
any name and re-sign a forged bundle (gpg and cosign draw the same line).
"""

from __future__ import annotations

import asyncio
import hashlib
import json
import os
import stat
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import datetime
from io import BytesIO
from pathlib import Path

from asn1crypto import cms
from asn1crypto import x509 as asn1_x509

from .certificates import is_self_signed, outside_validity, read_certificates
from .manifest import FINDINGS_NAME, MANIFEST_NAME, PDF_NAME, SIGNATURE_NAME, Manifest
from .reading import DOCUMENT, MANIFEST, SMALL, FileRefused, read_limited
from .text import visible
from .trust import trusted


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
    from cryptography.hazmat.primitives.serialization import Encoding

    # Read as every certificate is read: a regular file of bounded size (a FIFO given here hung verify).
    certs = read_certificates(path)
    if not certs:
        raise ValueError(f"{path} holds no certificate")
    return [asn1_x509.Certificate.load(c.public_bytes(Encoding.DER)) for c in certs]


def _anchors(extra: Sequence[Path]) -> list[tuple[asn1_x509.Certificate, str]]:
    """The trust anchors of this run, each with where it came from."""
    anchors = []
    for entry in trusted():
        anchors.extend((cert, "trust store") for cert in load_trust(entry.path))
    for path in extra:
        anchors.extend((cert, "--trust") for cert in load_trust(path))
    return anchors


def _context(roots: list[asn1_x509.Certificate]):
    from pyhanko_certvalidator import ValidationContext

    # Offline by design: a verification must give the same answer without a network.
    return ValidationContext(trust_roots=roots, allow_fetching=False, revocation_mode="soft-fail")


def _check_manifest_signature(folder: Path, manifest_bytes: bytes,
                              result: Verification) -> tuple[asn1_x509.Certificate, list[asn1_x509.Certificate]] | None:
    """Validate the detached CMS signature against its own signer; return the signer and the other certificates."""
    from pyhanko.sign.validation.generic_cms import async_validate_detached_cms

    try:
        info = cms.ContentInfo.load(read_limited(folder / SIGNATURE_NAME, SMALL))
        signed = info["content"]
        signer_info = signed["signer_infos"][0]
        sid = signer_info["sid"]
        certs = [c.chosen for c in signed["certificates"] if c.name == "certificate"]
        signer = next(c for c in certs if sid.name == "issuer_and_serial_number"
                      and c.issuer == sid.chosen["issuer"] and c.serial_number == sid.chosen["serial_number"].native)
        status = asyncio.run(async_validate_detached_cms(manifest_bytes, signed,
                                                         signer_validation_context=_context([signer])))
    except FileNotFoundError:
        result.fail(SIGNATURE_NAME, "missing")
        return None
    except FileRefused as exc:
        result.fail(SIGNATURE_NAME, f"refused: {exc}")
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
        result.fail(SIGNATURE_NAME, "the signer's certificate is not usable for signing (expired, or wrong key usage)")
        return None
    result.passed.append(f"{SIGNATURE_NAME}: valid CMS signature over {MANIFEST_NAME} by {signer.subject.human_friendly}")
    return signer, [c for c in certs if c is not signer]


def _check_pdf(path: Path, signer: asn1_x509.Certificate | None, result: Verification) -> None:
    from pyhanko.pdf_utils.reader import PdfFileReader
    from pyhanko.sign.validation import validate_pdf_signature
    from pyhanko.sign.validation.status import SignatureCoverageLevel

    name = path.name
    try:
        reader = PdfFileReader(BytesIO(read_limited(path, DOCUMENT)))
        signatures = reader.embedded_signatures
        if len(signatures) != 1:
            result.fail(name, f"expected one signature, found {len(signatures)}")
            return
        sig = signatures[0]
        status = validate_pdf_signature(sig, _context([sig.signer_cert]))
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
        result.fail(name, "the PDF signer's certificate is not usable for signing (expired, or wrong key usage)")
    elif signer is not None and _fingerprint(sig.signer_cert) != _fingerprint(signer):
        result.fail(name, "signed by a different certificate than the manifest")
    else:
        result.passed.append(f"{name}: certification signature valid, covers the entire file")


def _digests(path: Path, size: int | None, algorithms: Sequence[str]) -> tuple[int | None, list[str]]:
    """The size of ``path`` if it is a regular file (else None), and its hex digests if that size is ``size``.

    The checks are made on the open descriptor, so a FIFO or a device put in
    the file's place never blocks or floods the hash, and a file of another
    size is not hashed at all (no digests).
    """
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    with os.fdopen(fd, "rb") as fh:
        st = os.fstat(fh.fileno())
        if not stat.S_ISREG(st.st_mode):
            return None, []
        if size is not None and st.st_size != size:
            return st.st_size, []
        hashes = [hashlib.new(name) for name in algorithms]
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            for h in hashes:
                h.update(chunk)
    return st.st_size, [h.hexdigest() for h in hashes]


def _check_files(folder: Path, manifest: Manifest, result: Verification) -> None:
    listed = {f.name for f in manifest.files}
    for entry in manifest.files:
        path = folder / entry.name
        try:
            if Path(entry.name).is_absolute() or ".." in Path(entry.name).parts:
                result.fail(entry.name, "manifest names a file outside the bundle")
            else:
                found, digests = _digests(path, entry.size, ("sha256",))
                if found is None:
                    result.fail(entry.name, "not a regular file (a folder, FIFO or device in its place)")
                elif not digests:
                    result.fail(entry.name, f"has {found:,} bytes, not the {entry.size:,} the manifest records "
                                            f"(altered)")
                elif digests[0] != entry.sha256:
                    result.fail(entry.name, "SHA-256 does not match the manifest (altered)")
                else:
                    result.passed.append(f"{entry.name}: SHA-256 matches")
        except FileNotFoundError:
            result.fail(entry.name, "missing")
        except OSError as exc:
            # A name the file system refuses (too long, say) fails this check only; the others still run.
            result.fail(entry.name, f"cannot be read: {exc.strerror or exc}")
    for path in sorted(folder.iterdir()):
        if path.name not in listed and path.name not in (MANIFEST_NAME, SIGNATURE_NAME):
            result.fail(path.name, "not listed in the manifest")


def _check_evidence(evidence: Path, manifest: Manifest, result: Verification) -> None:
    """Hash the evidence in chunks, once it is known to be a regular file of the recorded size."""
    recorded = manifest.evidence
    try:
        found, digests = _digests(evidence, recorded.get("size"), ("sha256", "sha512"))
    except OSError as exc:
        result.fail("evidence", f"cannot read {evidence}: {exc.strerror or exc}")
        return
    if found is None:
        result.fail("evidence", f"{evidence} is not a regular file")
    elif not digests:
        result.fail("evidence", f"{evidence.name} has {found:,} bytes, not the {recorded['size']:,} recorded "
                                f"for {recorded.get('name')}")
    elif digests != [recorded.get("sha256"), recorded.get("sha512")]:
        result.fail("evidence", f"{evidence.name} does not match the SHA-256/SHA-512 recorded for {recorded.get('name')}")
    else:
        result.passed.append(f"evidence: {evidence.name} matches SHA-256 and SHA-512")


def _check_trust(signer: asn1_x509.Certificate, others: list[asn1_x509.Certificate],
                 anchors: list[tuple[asn1_x509.Certificate, str]], signatures_ok: bool, result: Verification) -> None:
    """Does the signer chain to a trusted certificate? Offline, at the current time."""
    from pyhanko_certvalidator import CertificateValidator
    from pyhanko_certvalidator.errors import PathBuildingError, PathValidationError, ValidationError

    who = f"{signer.subject.human_friendly}, SHA-256 {_fingerprint(signer)}"
    prefix = "signatures valid but " if signatures_ok else ""
    if not anchors:
        result.fail("signer", f"{prefix}signer not trusted: {who} (the trust store is empty; add a certificate with "
                              "`forensics keys trust add CERT` or give --trust CERT)")
        return
    validator = CertificateValidator(signer, intermediate_certs=others,
                                     validation_context=_context([cert for cert, _ in anchors]))
    try:
        path = asyncio.run(validator.async_validate_path())
    except (PathBuildingError, PathValidationError, ValidationError):
        result.fail("signer", f"{prefix}signer not trusted: {who}")
        return
    root = path.trust_anchor.authority.certificate if hasattr(path.trust_anchor.authority, "certificate") else None
    origin = next((where for cert, where in anchors if root is not None and cert.dump() == root.dump()), "trust store")
    result.passed.append(f"signer: {who}, trusted ({origin})")


def _check_validity(signer: asn1_x509.Certificate, created: str, result: Verification) -> None:
    """The signing certificate was valid when the bundle was signed (the manifest's time, not today's)."""
    from cryptography import x509

    try:
        at = datetime.fromisoformat(created.replace("Z", "+00:00"))
        if at.tzinfo is None:
            raise ValueError(created)
    except ValueError:
        result.fail(MANIFEST_NAME, f"records no readable signing time ({created[:40]!r})")
        return
    problem = outside_validity(x509.load_der_x509_certificate(signer.dump()), at)
    if problem:
        result.fail("signer", f"the signing certificate was {problem} when the bundle was signed ({created})")


def _check_outputs(folder: Path, manifest: Manifest, result: Verification) -> None:
    """Every produced document listed, and findings.json about the evidence the manifest names."""
    listed = {f.name for f in manifest.files}
    for name in manifest.outputs or []:
        if name not in listed:
            result.fail(name, "missing: the manifest records it as produced but does not list it")
    if FINDINGS_NAME in listed and (folder / FINDINGS_NAME).is_file():
        try:
            doc = json.loads(read_limited(folder / FINDINGS_NAME, DOCUMENT).decode("utf-8"))
            sha = doc["evidence"]["sha256"]
        except (OSError, ValueError, KeyError, TypeError, RecursionError):
            result.fail(FINDINGS_NAME, "unreadable: not the findings of a forensics run")
            return
        if sha != manifest.evidence.get("sha256"):
            result.fail(FINDINGS_NAME, "is about other evidence than the manifest names")


def verify_bundle(folder: Path, evidence: Path | None = None, trust: Path | Sequence[Path] = ()) -> Verification:
    """Run every check on the bundle in ``folder``; see the module docstring.

    Parameters
    ----------
    folder : Path
        The bundle.
    evidence : Path, optional
        The evidence photo, hashed and compared with the manifest.
    trust : Path or sequence of Path
        Certificates trusted for this run, besides the trust store's.

    Raises
    ------
    ValueError
        When a ``trust`` certificate cannot be read (a usage error, not a failed check).

    Examples
    --------
    >>> from pathlib import Path
    >>> result = verify_bundle(Path("out/left01"), evidence=Path("left01.jpg"),
    ...                        trust=Path("colleague.pem"))  # doctest: +SKIP
    >>> result.ok, [str(p) for p in result.problems]  # doctest: +SKIP
    (True, [])
    """
    result = Verification()
    anchors = _anchors([trust] if isinstance(trust, Path) else list(trust))
    try:
        manifest_bytes = read_limited(folder / MANIFEST_NAME, MANIFEST)
    except FileRefused as exc:
        result.fail(MANIFEST_NAME, f"refused: {exc}")
        return result
    except OSError:
        result.fail(MANIFEST_NAME, "missing")
        return result
    signed = _check_manifest_signature(folder, manifest_bytes, result)
    if signed is None:
        # An unauthenticated manifest says nothing about the other files; the
        # PDF's own signature can still be checked.
        if (folder / PDF_NAME).is_file():
            _check_pdf(folder / PDF_NAME, None, result)
        result.notes.append("files not compared with the manifest, whose signature failed")
        return result
    signer, others = signed
    try:
        manifest = Manifest.from_bytes(manifest_bytes)
    except (ValueError, UnicodeDecodeError) as exc:
        result.fail(MANIFEST_NAME, f"unreadable: {exc}")
        return result
    if manifest.signer.get("sha256_fingerprint") != _fingerprint(signer):
        result.fail(MANIFEST_NAME, "names a different signing certificate than the one that signed it")
    _check_validity(signer, manifest.created, result)
    _check_files(folder, manifest, result)
    _check_outputs(folder, manifest, result)
    pdf_failed = False
    if any(f.name == PDF_NAME for f in manifest.files) and (folder / PDF_NAME).is_file():
        before = len(result.problems)
        _check_pdf(folder / PDF_NAME, signer, result)
        pdf_failed = any(p.subject == PDF_NAME for p in result.problems[before:])
    _check_trust(signer, others, anchors, not pdf_failed, result)
    if evidence is not None:
        _check_evidence(evidence, manifest, result)
    _check_signer_record(signer, manifest, result)
    return result


def _check_signer_record(signer: asn1_x509.Certificate, manifest: Manifest, result: Verification) -> None:
    """The manifest's description of its signer is the certificate's, and what is said of the signer comes from it."""
    from cryptography import x509

    cert = x509.load_der_x509_certificate(signer.dump())
    subject, self_signed = cert.subject.rfc4514_string(), is_self_signed(cert)
    recorded = manifest.signer
    if recorded.get("subject") != subject or bool(recorded.get("self_signed")) != self_signed:
        result.fail(MANIFEST_NAME, f"describes its signer as '{visible(str(recorded.get('subject')))}' "
                                   f"(self-signed: {bool(recorded.get('self_signed'))}), but the certificate that "
                                   f"signed it is '{visible(subject)}' (self-signed: {self_signed})")
    if self_signed:
        result.notes.append(f"the signing certificate is self-signed ({visible(subject)}, "
                            f"SHA-256 {_fingerprint(signer)})")
