"""The examiner's signing key: creation, loading, and the two signatures it makes.

A report bundle carries two signatures by the same certificate: a PAdES
certification signature inside ``report.pdf`` (DocMDP "no changes"), and a
detached CMS signature over ``manifest.json`` that ``openssl cms -verify``
checks. Keys are ECDSA P-256 (fast; accepted by poppler's ``pdfsig``, which
rejects Ed25519) or RSA-3072.

With no key given, a per-user self-signed key is made on first use under the
configuration folder (``$FORENSICS_HOME``, else ``$XDG_CONFIG_HOME/forensics``,
else ``~/.config/forensics``); the report then says plainly that its
certificate is self-signed.
"""

from __future__ import annotations

import asyncio
import contextlib
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from io import BytesIO
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec, rsa
from cryptography.hazmat.primitives.serialization import pkcs12
from cryptography.x509.oid import NameOID

from . import trust
from .atomic import write_atomic, write_new
from .certificates import fingerprint, is_self_signed, outside_validity
from .reading import SMALL, FileRefused, read_limited
from .defaults import KEY_TYPES
from .home import config_dir

DEFAULT_KEY_NAME = "examiner"
_VALIDITY_DAYS = 730
_SIGNATURE_FIELD = "ExaminerCertification"


class SigningError(Exception):
    """The key cannot be made, loaded or used; the message is one line for the user."""


class KeyExistsError(SigningError):
    """A new key was to be stored where a key already is."""


@dataclass(frozen=True)
class ExaminerKey:
    """A loaded signing key and what the report says about it.

    Attributes
    ----------
    cert : cryptography.x509.Certificate
        The signing certificate.
    pkcs12_data, password : bytes, bytes or None
        The PKCS#12 it came from, kept so that pyHanko loads the same material.
    source : str
        Where the key came from, in words (a path).
    created_now : bool
        True when this call made the per-user key (the CLI says so once).
    """

    cert: x509.Certificate
    pkcs12_data: bytes
    password: bytes | None
    source: str
    created_now: bool = False

    @property
    def subject(self) -> str:
        return self.cert.subject.rfc4514_string()

    @property
    def fingerprint(self) -> str:
        return fingerprint(self.cert)

    @property
    def self_signed(self) -> bool:
        return is_self_signed(self.cert)

    @property
    def organisation(self) -> str | None:
        values = self.cert.subject.get_attributes_for_oid(NameOID.ORGANIZATION_NAME)
        return str(values[0].value) if values else None

    @property
    def cert_pem(self) -> bytes:
        return self.cert.public_bytes(serialization.Encoding.PEM)

    def pyhanko_signer(self):
        from pyhanko.sign import signers

        try:
            return signers.SimpleSigner.load_pkcs12_data(self.pkcs12_data, other_certs=(), passphrase=self.password)
        except ValueError as exc:
            raise SigningError(f"cannot load the key {self.source}: {exc}") from None


def _new_private_key(key_type: str):
    if key_type == "ecdsa-p256":
        return ec.generate_private_key(ec.SECP256R1())
    if key_type == "rsa-3072":
        return rsa.generate_private_key(public_exponent=65537, key_size=3072)
    raise SigningError(f"unknown key type {key_type!r}; choose one of {', '.join(KEY_TYPES)}")


def create_self_signed(name: str, organisation: str, key_type: str = "ecdsa-p256",
                       password: bytes | None = None) -> tuple[bytes, x509.Certificate]:
    """A self-signed examiner certificate and its PKCS#12, for trial use.

    The certificate allows digital signatures and non-repudiation (what PDF
    and S/MIME validators look for) and is no CA.
    """
    key = _new_private_key(key_type)
    subject = x509.Name([
        x509.NameAttribute(NameOID.COMMON_NAME, name),
        x509.NameAttribute(NameOID.ORGANIZATION_NAME, organisation),
    ])
    now = datetime.now(timezone.utc)
    public = key.public_key()
    cert = (
        x509.CertificateBuilder()
        .subject_name(subject)
        .issuer_name(subject)
        .public_key(public)
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - timedelta(minutes=5))
        .not_valid_after(now + timedelta(days=_VALIDITY_DAYS))
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(
            x509.KeyUsage(digital_signature=True, content_commitment=True, key_encipherment=False,
                          data_encipherment=False, key_agreement=False, key_cert_sign=False, crl_sign=False,
                          encipher_only=False, decipher_only=False),
            critical=True,
        )
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(public), critical=False)
        .sign(key, hashes.SHA256())
    )
    encryption = (serialization.BestAvailableEncryption(password) if password
                  else serialization.NoEncryption())
    p12 = pkcs12.serialize_key_and_certificates(name.encode("utf-8"), key, cert, None, encryption)
    return p12, cert


def write_key_files(folder: Path, p12: bytes, cert: x509.Certificate, stem: str = DEFAULT_KEY_NAME) -> tuple[Path, Path]:
    """Write ``stem.p12`` (mode 0600: it holds the private key) and ``stem.pem`` (the certificate).

    Raises
    ------
    KeyExistsError
        When ``stem.p12`` exists, even if another process stored it a moment
        ago; then nothing is written.
    """
    folder.mkdir(parents=True, exist_ok=True)
    p12_path = folder / f"{stem}.p12"
    try:
        write_new(p12_path, p12)
    except FileExistsError:
        raise KeyExistsError(f"{p12_path} exists; refusing to overwrite a signing key") from None
    # Only the process that stored the PKCS#12 gets here, so the certificate
    # beside it is always that key's, never another process's.
    pem_path = write_atomic(folder / f"{stem}.pem", cert.public_bytes(serialization.Encoding.PEM))
    return p12_path, pem_path


def load_key(path: Path, password: bytes | None) -> ExaminerKey:
    """Load a PKCS#12 file; the certificate must carry an ECDSA P-256/P-384 or RSA (>= 2048 bit) key."""
    try:
        data = read_limited(path, SMALL)
    except FileRefused as exc:
        raise SigningError(f"cannot read the key: {exc}") from None
    except OSError as exc:
        raise SigningError(f"cannot read the key {path}: {exc.strerror or exc}") from None
    try:
        _, cert, _ = pkcs12.load_key_and_certificates(data, password)
    except ValueError:
        raise SigningError(f"cannot open the key {path}: wrong password or not a PKCS#12 file") from None
    if cert is None:
        raise SigningError(f"the key {path} holds no certificate")
    public = cert.public_key()
    if not isinstance(public, (ec.EllipticCurvePublicKey, rsa.RSAPublicKey)):
        raise SigningError(f"the key {path} is {type(public).__name__}; use ECDSA P-256 or RSA-3072 "
                           "(poppler rejects Ed25519 signatures)")
    if isinstance(public, rsa.RSAPublicKey) and public.key_size < 2048:
        raise SigningError(f"the RSA key {path} has {public.key_size} bits; at least 2048 are needed")
    # A signature made outside the certificate's validity would be refused by any verifier.
    problem = outside_validity(cert)
    if problem:
        raise SigningError(f"the certificate of the key {path} is {problem}: make or obtain a new key")
    return ExaminerKey(cert=cert, pkcs12_data=data, password=password, source=str(path))


UNNAMED_EXAMINER = "unnamed examiner"


def default_key_path() -> Path:
    return config_dir() / f"{DEFAULT_KEY_NAME}.p12"


def default_key(examiner: str | None = None, organisation: str | None = None,
                password: bytes | None = None) -> ExaminerKey:
    """The per-user key, made (self-signed, no password, mode 0600) on first use, and trusted.

    ``password`` opens an existing per-user key that ``forensics keys create``
    protected with one. The key is put into the trust store when it is made,
    and once more if the store does not exist yet (a key made before trust
    stores existed); a key the examiner later removed from the store stays out.
    Of runs that start together on a fresh account, one makes the key and the
    others sign with it.
    """
    path = default_key_path()
    if path.exists():
        return _stored_default_key(path, password)
    # A login name ("root") is not an examiner's identity: a key made without
    # one says so, and reports signed with it say no examiner is named.
    name = examiner or UNNAMED_EXAMINER
    p12, cert = create_self_signed(name, organisation or "unspecified organisation (trial key)")
    try:
        write_key_files(path.parent, p12, cert)
    except KeyExistsError:
        # A run started at the same time stored its key first: that is the
        # examiner's key now, and this run's would sign reports no key on
        # disk can be matched with.
        return _stored_default_key(path, password)
    except OSError as exc:
        raise SigningError(f"cannot store a new per-user key in {path.parent}: {exc.strerror or exc}") from None
    _trust(cert)
    # The key this run stored and trusted, whatever the file holds by now.
    return ExaminerKey(cert, p12, None, str(path), created_now=True)


def _stored_default_key(path: Path, password: bytes | None) -> ExaminerKey:
    key = load_key(path, password)
    if not trust.store_dir().exists():
        _trust(key.cert)
    pem = path.with_suffix(".pem")
    if not pem.exists():
        # The run that made the key was stopped between storing it and
        # writing its certificate beside it. The certificate is the key's
        # own, so it is written again for the examiner to share; a folder
        # that cannot take it must not stop the signing.
        with contextlib.suppress(OSError):
            write_atomic(pem, key.cert_pem)
    return key


def _trust(cert: x509.Certificate) -> None:
    try:
        trust.trust_certificate(cert)
    except trust.TrustError as exc:
        raise SigningError(str(exc)) from None


def sign_pdf(pdf: bytes, key: ExaminerKey, *, reason: str, location: str | None = None,
             tsa_url: str | None = None) -> bytes:
    """Certify ``pdf`` (PAdES, DocMDP P1: no changes permitted) and return the signed bytes.

    The signature is an incremental update; it covers the whole file as
    written, so any byte changed or appended afterwards breaks it.
    """
    from pyhanko.pdf_utils.incremental_writer import IncrementalPdfFileWriter
    from pyhanko.sign import signers, timestamps
    from pyhanko.sign.fields import MDPPerm, SigSeedSubFilter

    meta = signers.PdfSignatureMetadata(
        field_name=_SIGNATURE_FIELD,
        md_algorithm="sha256",
        certify=True,
        docmdp_permissions=MDPPerm.NO_CHANGES,
        subfilter=SigSeedSubFilter.PADES,
        reason=reason,
        location=location,
        name=_common_name(key.cert),
    )
    timestamper = timestamps.HTTPTimeStamper(tsa_url) if tsa_url else None
    writer = IncrementalPdfFileWriter(BytesIO(pdf))
    out = signers.sign_pdf(writer, meta, signer=key.pyhanko_signer(), timestamper=timestamper)
    return out.getvalue()


def sign_detached(data: bytes, key: ExaminerKey, tsa_url: str | None = None) -> bytes:
    """A detached CMS (PKCS#7) signature over ``data``, DER-encoded.

    Check it with ``openssl cms -verify -binary -inform DER -in SIG -content DATA -CAfile CERT``.
    """
    from pyhanko.sign import timestamps

    timestamper = timestamps.HTTPTimeStamper(tsa_url) if tsa_url else None
    signer = key.pyhanko_signer()
    content_info = asyncio.run(signer.async_sign_general_data(data, "sha256", detached=True, timestamper=timestamper))
    return content_info.dump()


def _common_name(cert: x509.Certificate) -> str:
    values = cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    return str(values[0].value) if values else cert.subject.rfc4514_string()

