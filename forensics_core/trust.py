"""The trust store: the certificates whose signatures ``verify`` accepts as naming the signer.

A valid signature proves that the bundle is unchanged since it was signed; it
says nothing of who signed it, since anyone can make a key with any name. As
with gpg's keyring and cosign's trusted roots, ``verify`` therefore passes a
bundle only when its signer chains to a certificate the examiner chose to
trust: one in this store (``forensics keys trust add``), or one given with
``--trust`` for a single run. The examiner's own key is trusted when it is
made.

The store is a folder, ``trusted/`` under the configuration folder (see
:func:`forensics_core.home.config_dir`), holding one PEM file per
certificate, named by its SHA-256 fingerprint, so that a certificate is held
once and a listing needs no index.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import serialization

from . import certificates
from .atomic import write_atomic
from .certificates import fingerprint, is_self_signed
from .home import config_dir

STORE_NAME = "trusted"


class TrustError(Exception):
    """A certificate cannot be read, added or removed; the message is one line for the user."""


@dataclass(frozen=True)
class TrustedCertificate:
    """One certificate of the store.

    Attributes
    ----------
    path : Path
        Its PEM file in the store.
    subject : str
        RFC 4514 subject.
    fingerprint : str
        SHA-256 of the DER certificate, colon-separated upper-case hex.
    self_signed : bool
    not_after : str
        End of validity, ISO 8601 UTC.
    """

    path: Path
    subject: str
    fingerprint: str
    self_signed: bool
    not_after: str

    @classmethod
    def of(cls, cert: x509.Certificate, path: Path) -> TrustedCertificate:
        return cls(path=path, subject=cert.subject.rfc4514_string(), fingerprint=fingerprint(cert),
                   self_signed=is_self_signed(cert),
                   not_after=cert.not_valid_after_utc.strftime("%Y-%m-%dT%H:%M:%SZ"))


def store_dir() -> Path:
    """The store's folder (it may not exist yet)."""
    return config_dir() / STORE_NAME


def _file_name(cert: x509.Certificate) -> str:
    return fingerprint(cert).replace(":", "") + ".pem"


def read_certificates(path: Path) -> list[x509.Certificate]:
    """The certificates of a PEM or DER file; :class:`TrustError` when there are none."""
    try:
        return certificates.read_certificates(path)
    except ValueError as exc:
        raise TrustError(str(exc)) from None


def trust_certificate(cert: x509.Certificate) -> TrustedCertificate:
    """Put ``cert`` into the store; adding a certificate already there changes nothing."""
    folder = store_dir()
    target = folder / _file_name(cert)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if not target.exists():
            write_atomic(target, cert.public_bytes(serialization.Encoding.PEM))
    except OSError as exc:
        raise TrustError(f"cannot write to the trust store {folder}: {exc.strerror or exc}") from None
    return TrustedCertificate.of(cert, target)


def add(path: Path) -> list[TrustedCertificate]:
    """Trust every certificate in the file at ``path``."""
    return [trust_certificate(cert) for cert in read_certificates(path)]


def trusted() -> list[TrustedCertificate]:
    """The store's certificates, by subject; unreadable files in the store are ignored."""
    folder = store_dir()
    found = []
    for path in sorted(folder.glob("*.pem")) if folder.is_dir() else []:
        try:
            found.extend(TrustedCertificate.of(cert, path) for cert in read_certificates(path))
        except TrustError:
            continue
    return sorted(found, key=lambda t: (t.subject, t.fingerprint))


def _normalise(text: str) -> str:
    return "".join(ch for ch in text.upper() if ch in "0123456789ABCDEF")


def remove(which: str) -> list[TrustedCertificate]:
    """Stop trusting certificates, named by a certificate file or by their SHA-256 fingerprint.

    A fingerprint may be given with or without colons, or as a prefix of at
    least 8 hex digits when that prefix names one certificate.

    Raises
    ------
    TrustError
        When nothing in the store matches, or a prefix matches several.
    """
    entries = trusted()
    if Path(which).is_file():
        wanted = {fingerprint(c) for c in read_certificates(Path(which))}
        chosen = [e for e in entries if e.fingerprint in wanted]
    else:
        prefix = _normalise(which)
        if len(prefix) < 8:
            raise TrustError(f"{which!r} is neither a certificate file nor a SHA-256 fingerprint (8 hex digits at least)")
        chosen = [e for e in entries if _normalise(e.fingerprint).startswith(prefix)]
        if len({e.fingerprint for e in chosen}) > 1:
            raise TrustError(f"{which!r} matches {len(chosen)} trusted certificates; give more of the fingerprint")
    if not chosen:
        raise TrustError(f"no trusted certificate matches {which!r}")
    for entry in chosen:
        try:
            entry.path.unlink()
        except FileNotFoundError:
            pass
        except OSError as exc:
            raise TrustError(f"cannot remove {entry.path}: {exc.strerror or exc}") from None
    return chosen
