"""X.509 certificates as the signing key, the trust store and ``verify`` see them."""

from __future__ import annotations

from datetime import datetime, timezone
from pathlib import Path

from cryptography import x509
from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives import hashes

from .reading import SMALL, FileRefused, read_limited


def fingerprint(cert: x509.Certificate) -> str:
    """SHA-256 fingerprint of the DER certificate, colon-separated upper-case hex (as openssl prints it)."""
    digest = cert.fingerprint(hashes.SHA256()).hex().upper()
    return ":".join(digest[i : i + 2] for i in range(0, len(digest), 2))


def outside_validity(cert: x509.Certificate, at: datetime | None = None) -> str | None:
    """Why ``cert`` is not valid at ``at`` (default now), naming its dates, or None when it is."""
    at = at or datetime.now(timezone.utc)
    start, end = cert.not_valid_before_utc, cert.not_valid_after_utc
    if at < start:
        return f"not valid until {start:%Y-%m-%d %H:%M} UTC (valid {start:%Y-%m-%d} to {end:%Y-%m-%d})"
    if at > end:
        return f"expired on {end:%Y-%m-%d %H:%M} UTC (valid {start:%Y-%m-%d} to {end:%Y-%m-%d})"
    return None


def is_self_signed(cert: x509.Certificate) -> bool:
    if cert.issuer != cert.subject:
        return False
    try:
        cert.verify_directly_issued_by(cert)
    except (ValueError, TypeError, InvalidSignature):
        return False
    return True


def read_certificates(path: Path) -> list[x509.Certificate]:
    """The certificates of a PEM file (one or more) or of a DER file.

    Raises
    ------
    ValueError
        When the file cannot be read or holds no certificate; the message is one line.
    """
    try:
        data = read_limited(path, SMALL)
    except FileRefused as exc:
        raise ValueError(f"cannot read the certificate: {exc}") from None
    except OSError as exc:
        raise ValueError(f"cannot read {path}: {exc.strerror or exc}") from None
    try:
        if b"-----BEGIN" in data:
            return x509.load_pem_x509_certificates(data)
        return [x509.load_der_x509_certificate(data)]
    except ValueError:
        raise ValueError(f"{path} holds no readable certificate (PEM or DER)") from None
