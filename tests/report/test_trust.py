"""Signer trust (issue 16, item 13): a valid signature by an untrusted signer is not a verified bundle."""

import json
from datetime import datetime, timedelta, timezone

import pytest
from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.hazmat.primitives.serialization import NoEncryption, pkcs12
from cryptography.x509.oid import NameOID

from forensics_core import signing, trust
from forensics_core.manifest import MANIFEST_NAME, PDF_NAME, SIGNATURE_NAME, SIGNER_CERT_NAME, sha256_file
from report_helpers import make_bundle, run


def forge(folder, key, drop=(PDF_NAME,), keep_outputs=False):
    """What an attacker does: rewrite the verdict, drop files, put their certificate in and re-sign the manifest."""
    findings = json.loads((folder / "findings.json").read_text())
    findings["verdict"]["label"] = "inconsistent"
    (folder / "findings.json").write_text(json.dumps(findings))
    for name in drop:
        (folder / name).unlink()
    (folder / SIGNER_CERT_NAME).write_bytes(key.cert_pem)
    manifest = json.loads((folder / MANIFEST_NAME).read_text())
    manifest["signer"] = {"subject": key.subject, "sha256_fingerprint": key.fingerprint, "self_signed": True}
    manifest["files"] = [{"name": f["name"], "size": (folder / f["name"]).stat().st_size,
                          "sha256": sha256_file(folder / f["name"])}
                         for f in manifest["files"] if f["name"] not in drop]
    if not keep_outputs:
        manifest["outputs"] = [n for n in manifest["outputs"] if n not in drop]
    data = json.dumps(manifest).encode()
    (folder / MANIFEST_NAME).write_bytes(data)
    (folder / SIGNATURE_NAME).write_bytes(signing.sign_detached(data, key))


def attacker_key(tmp_path, name="Mallory"):
    p12, cert = signing.create_self_signed(name, "Nowhere")
    p12_path, pem = signing.write_key_files(tmp_path / name, p12, cert)
    return signing.load_key(p12_path, None), pem


def test_a_bundle_re_signed_by_an_unknown_key_is_not_verified(bundle_copy, tmp_path):
    mallory, _ = attacker_key(tmp_path)
    forge(bundle_copy, mallory)
    out = run("verify", bundle_copy)
    assert out.returncode == 1
    assert out.stderr.strip().splitlines() == [
        f"forensics: error: signer: signatures valid but signer not trusted: Organization: Nowhere, "
        f"Common Name: Mallory, SHA-256 {mallory.fingerprint}"]
    assert "verified" not in out.stdout


def test_a_missing_output_fails_even_when_the_signer_is_trusted(bundle_copy, tmp_path):
    mallory, pem = attacker_key(tmp_path)
    forge(bundle_copy, mallory, keep_outputs=True)
    out = run("verify", bundle_copy, "--trust", pem)
    assert out.returncode == 1
    assert out.stderr.strip().splitlines() == [
        "forensics: error: report.pdf: missing: the manifest records it as produced but does not list it"]


def test_findings_about_other_evidence_fail(bundle_copy, tmp_path):
    mallory, pem = attacker_key(tmp_path)
    findings = json.loads((bundle_copy / "findings.json").read_text())
    findings["evidence"]["sha256"] = "0" * 64
    (bundle_copy / "findings.json").write_text(json.dumps(findings))
    forge(bundle_copy, mallory, drop=())
    out = run("verify", bundle_copy, "--trust", pem)
    assert out.returncode == 1
    assert "forensics: error: findings.json: is about other evidence than the manifest names" in out.stderr


def test_trust_store_commands(tmp_path, isolated_home, key):
    mallory, pem = attacker_key(tmp_path)
    listed = run("keys", "trust", "list")
    assert listed.returncode == 0 and key.fingerprint in listed.stdout and mallory.fingerprint not in listed.stdout
    added = run("keys", "trust", "add", pem)
    assert added.returncode == 0 and added.stdout.startswith(f"trusted: {mallory.fingerprint}  O=Nowhere,CN=Mallory")
    assert run("keys", "trust", "add", pem).returncode == 0, "adding twice changes nothing"
    assert len(list((isolated_home / "trusted").glob("*.pem"))) == 2
    assert mallory.fingerprint in run("keys", "trust", "list").stdout

    prefix = mallory.fingerprint.replace(":", "")[:10].lower()
    removed = run("keys", "trust", "remove", prefix)
    assert removed.returncode == 0 and removed.stdout.startswith(f"removed: {mallory.fingerprint}")
    assert mallory.fingerprint not in run("keys", "trust", "list").stdout

    again = run("keys", "trust", "remove", prefix)
    assert again.returncode == 1 and again.stderr.strip() == (
        f"forensics: error: keys trust remove: no trusted certificate matches '{prefix}'")
    short = run("keys", "trust", "remove", "ab")
    assert short.returncode == 1 and "8 hex digits at least" in short.stderr
    assert run("keys", "trust", "remove", key_pem := tmp_path / "k.pem").returncode == 1
    key_pem.write_bytes(key.cert_pem)
    assert run("keys", "trust", "remove", key_pem).returncode == 0
    assert "is empty" in run("keys", "trust", "list").stdout

    junk = tmp_path / "junk.pem"
    junk.write_text("not a certificate")
    bad = run("keys", "trust", "add", junk)
    assert bad.returncode == 1 and len(bad.stderr.strip().splitlines()) == 1
    assert "holds no readable certificate" in bad.stderr and "Traceback" not in bad.stderr


def test_the_examiner_s_own_key_is_trusted_when_made_and_a_removal_sticks(tmp_path, data_dir, isolated_home):
    photo = data_dir / "exif" / "Canon_40D.jpg"
    trust.remove(trust.trusted()[0].fingerprint)
    (isolated_home / "trusted").rmdir()
    made = run("analyze", photo, "--out", tmp_path / "a", "--detectors", "", "--format", "html")
    assert made.returncode == 0, made.stderr
    own = signing.load_key(isolated_home / "examiner.p12", None)
    assert [t.fingerprint for t in trust.trusted()] == [own.fingerprint]
    assert run("verify", tmp_path / "a" / "Canon_40D").returncode == 0

    trust.remove(own.fingerprint)
    assert run("analyze", photo, "--out", tmp_path / "b", "--detectors", "", "--format", "html").returncode == 0
    assert trust.trusted() == []
    assert run("verify", tmp_path / "b" / "Canon_40D").returncode == 1


def test_a_key_made_before_trust_stores_is_trusted_on_first_use(tmp_path, data_dir, isolated_home):
    trust.remove(trust.trusted()[0].fingerprint)
    (isolated_home / "trusted").rmdir()
    p12, cert = signing.create_self_signed("Old Key", "Lab")
    signing.write_key_files(isolated_home, p12, cert)
    assert not (isolated_home / "trusted").exists()
    out = run("analyze", data_dir / "exif" / "Canon_40D.jpg", "--out", tmp_path / "o", "--detectors", "",
              "--format", "html")
    assert out.returncode == 0, out.stderr
    assert [t.subject for t in trust.trusted()] == ["O=Lab,CN=Old Key"]


def _issued_key(tmp_path):
    """A CA certificate and an examiner key it issued (PKCS#12 path)."""
    now = datetime.now(timezone.utc)
    ca_key = ec.generate_private_key(ec.SECP256R1())
    ca_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "Lab Root CA")])
    ca = (x509.CertificateBuilder().subject_name(ca_name).issuer_name(ca_name).public_key(ca_key.public_key())
          .serial_number(1).not_valid_before(now - timedelta(hours=1)).not_valid_after(now + timedelta(days=30))
          .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True)
          .add_extension(x509.KeyUsage(digital_signature=False, content_commitment=False, key_encipherment=False,
                                       data_encipherment=False, key_agreement=False, key_cert_sign=True,
                                       crl_sign=True, encipher_only=False, decipher_only=False), critical=True)
          .sign(ca_key, hashes.SHA256()))
    leaf_key = ec.generate_private_key(ec.SECP256R1())
    leaf = (x509.CertificateBuilder()
            .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "Issued Examiner"),
                                     x509.NameAttribute(NameOID.ORGANIZATION_NAME, "Lab")]))
            .issuer_name(ca_name).public_key(leaf_key.public_key()).serial_number(2)
            .not_valid_before(now - timedelta(hours=1)).not_valid_after(now + timedelta(days=30))
            .add_extension(x509.KeyUsage(digital_signature=True, content_commitment=True, key_encipherment=False,
                                         data_encipherment=False, key_agreement=False, key_cert_sign=False,
                                         crl_sign=False, encipher_only=False, decipher_only=False), critical=True)
            .sign(ca_key, hashes.SHA256()))
    p12 = tmp_path / "issued.p12"
    p12.write_bytes(pkcs12.serialize_key_and_certificates(b"issued", leaf_key, leaf, [ca], NoEncryption()))
    ca_pem = tmp_path / "ca.pem"
    ca_pem.write_bytes(ca.public_bytes(serialization.Encoding.PEM))
    return p12, ca_pem


def test_a_signer_issued_by_a_trusted_ca_is_trusted(tmp_path, data_dir):
    p12, ca_pem = _issued_key(tmp_path)
    folder = make_bundle(data_dir / "exif" / "Canon_40D.jpg", tmp_path / "b", signing.load_key(p12, None),
                         plugins=())
    assert run("verify", folder).returncode == 1
    assert run("keys", "trust", "add", ca_pem).returncode == 0
    out = run("verify", folder)
    assert out.returncode == 0, out.stderr
    assert "Common Name: Issued Examiner" in out.stdout and "trusted (trust store)" in out.stdout


def _fifo_or_device(path, kind):
    import os

    path.unlink(missing_ok=True)
    if kind == "fifo":
        os.mkfifo(path)
    else:
        path.symlink_to("/dev/zero")


@pytest.mark.parametrize("kind", ["fifo", "device"])
@pytest.mark.parametrize("name", [MANIFEST_NAME, SIGNATURE_NAME])
def test_a_manifest_or_signature_that_is_no_regular_file_is_refused_at_once(bundle_copy, name, kind):
    # A FIFO hung verify; a link to /dev/zero grew to 3.8 GB before a MemoryError.
    _fifo_or_device(bundle_copy / name, kind)
    out = run("verify", bundle_copy)
    assert out.returncode == 1, out.stdout + out.stderr
    assert f"{name}: refused: " in out.stderr and "is not a regular file" in out.stderr
    assert "Traceback" not in out.stderr and "internal error" not in out.stderr


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_certificate_or_key_that_is_no_regular_file_is_refused_at_once(tmp_path, isolated_home, bundle, kind):
    path = tmp_path / "cert.pem"
    _fifo_or_device(path, kind)
    for args in (("keys", "trust", "add", path), ("verify", bundle, "--trust", path)):
        out = run(*args)
        assert out.returncode != 0 and "is not a regular file" in out.stderr, (args, out.stderr)
        assert "Traceback" not in out.stderr
    with pytest.raises(signing.SigningError, match="is not a regular file"):
        signing.load_key(path, None)


def _dated_key(tmp_path, before: timedelta, after: timedelta):
    """A self-signed examiner key valid from now + before to now + after (PKCS#12 path, PEM path)."""
    now = datetime.now(timezone.utc)
    k = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "Dated Examiner")])
    cert = (x509.CertificateBuilder().subject_name(name).issuer_name(name).public_key(k.public_key())
            .serial_number(7).not_valid_before(now + before).not_valid_after(now + after)
            .sign(k, hashes.SHA256()))
    p12 = tmp_path / "dated.p12"
    p12.write_bytes(pkcs12.serialize_key_and_certificates(b"dated", k, cert, None, NoEncryption()))
    pem = tmp_path / "dated.pem"
    pem.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    return p12, pem


@pytest.mark.parametrize("when", ["expired", "not yet valid"])
def test_a_certificate_outside_its_validity_is_warned_of_refused_for_signing(tmp_path, isolated_home, when):
    before, after = ((-timedelta(days=400), -timedelta(days=30)) if when == "expired" else
                     (timedelta(days=400), timedelta(days=800)))
    p12, pem = _dated_key(tmp_path, before, after)
    out = run("keys", "trust", "add", pem)
    assert out.returncode == 0 and "warning: " in out.stderr
    assert ("expired on " if when == "expired" else "not valid until ") in out.stderr
    with pytest.raises(signing.SigningError, match="expired on|not valid until"):
        signing.load_key(p12, None)


def test_verify_fails_a_bundle_signed_outside_the_signer_s_validity(bundle_copy, tmp_path, key):
    # The manifest's signing time is the reference: a bundle signed after the certificate expired fails.
    manifest = json.loads((bundle_copy / MANIFEST_NAME).read_text())
    manifest["created"] = "2099-01-01T00:00:00Z"
    data = json.dumps(manifest).encode()
    (bundle_copy / MANIFEST_NAME).write_bytes(data)
    (bundle_copy / SIGNATURE_NAME).write_bytes(signing.sign_detached(data, key))
    out = run("verify", bundle_copy)
    assert out.returncode == 1
    assert "the signing certificate was expired on " in out.stderr and "2099-01-01" in out.stderr


def test_a_manifest_naming_a_file_too_long_for_the_file_system_fails_that_file_only(bundle_copy, key):
    manifest = json.loads((bundle_copy / MANIFEST_NAME).read_text())
    long_name = "n" * 300
    manifest["files"].append({"name": long_name, "size": 1, "sha256": "0" * 64})
    manifest["files"].append({"name": "/".join(["d" * 200] * 25), "size": 1, "sha256": "0" * 64})
    data = json.dumps(manifest).encode()
    (bundle_copy / MANIFEST_NAME).write_bytes(data)
    (bundle_copy / SIGNATURE_NAME).write_bytes(signing.sign_detached(data, key))
    out = run("verify", bundle_copy)
    assert out.returncode == 1 and "internal error" not in out.stderr, out.stderr
    assert f"{long_name}: cannot be read: " in out.stderr
    assert "findings.json" not in out.stderr and "signer" not in out.stderr.split("cannot be read")[0]
