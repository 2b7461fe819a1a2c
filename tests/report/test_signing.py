"""Signatures and verification with real keys, real PDFs and the standard tools (pdfsig, openssl).

What pdfsig is asked: poppler checks the signature with NSS and has no trust
store holding our self-signed test certificate, so the tests require
"Signature is Valid." and "Total document signed" and accept that the
certificate is reported untrusted/unknown ("signature is valid, certificate
not trusted"). Trust is tested with pyHanko and openssl, which are given the
certificate explicitly.
"""

import json
import shutil
import subprocess
from io import BytesIO
from pathlib import Path

import pytest
from cryptography.hazmat.primitives.asymmetric import ed25519
from cryptography.hazmat.primitives.serialization import NoEncryption, pkcs12

from forensics_core import signing, trust
from forensics_core.manifest import MANIFEST_NAME, SIGNATURE_NAME
from forensics_core.verify import verify_bundle
from report_helpers import FORENSICS, make_bundle, pdf_pages_text, run

KINDS = ["findings.json", "report.html", "report.pdf", "sectioned-overlay.png", "sectioned-plot.svg", "signer.pem",
         MANIFEST_NAME, SIGNATURE_NAME]


def flip_byte(path: Path, where: float = 0.5) -> None:
    data = bytearray(path.read_bytes())
    data[int(len(data) * where)] ^= 0x01
    path.write_bytes(bytes(data))


def failures(result) -> list[str]:
    return [str(p) for p in result.problems]


def test_untouched_bundle_verifies_by_the_store_or_by_trust_for_the_run(bundle, data_dir, key_files, key):
    plain = run("verify", bundle, "--evidence", data_dir / "exif" / "Canon_40D.jpg")
    assert plain.returncode == 0, plain.stderr
    assert plain.stdout.strip().endswith(f"verified: {bundle}")
    assert "report.pdf: certification signature valid, covers the entire file" in plain.stdout
    assert f"SHA-256 {key.fingerprint}, trusted (trust store)" in plain.stdout and "self-signed" in plain.stdout
    assert plain.stderr == ""
    trust.remove(key.fingerprint)
    once = run("verify", bundle, "--trust", key_files[1])
    assert once.returncode == 0, once.stderr
    assert "trusted (--trust)" in once.stdout


def test_manifest_lists_every_file_and_the_evidence(bundle, data_dir):
    manifest = json.loads((bundle / MANIFEST_NAME).read_text())
    listed = {f["name"] for f in manifest["files"]}
    on_disk = {p.name for p in bundle.iterdir()} - {MANIFEST_NAME, SIGNATURE_NAME}
    assert listed == on_disk
    assert {"findings.json", "report.html", "report.pdf", "signer.pem", "sectioned-overlay.png"} <= listed
    from forensics_core.evidence import load_evidence

    info = load_evidence(data_dir / "exif" / "Canon_40D.jpg").info
    assert manifest["evidence"]["sha256"] == info.sha256 and manifest["evidence"]["sha512"] == info.sha512


@pytest.mark.parametrize("name", KINDS)
def test_one_flipped_byte_in_any_file_fails_and_is_named(bundle_copy, name):
    flip_byte(bundle_copy / name)
    out = run("verify", bundle_copy)
    assert out.returncode == 1
    lines = out.stderr.strip().splitlines()
    assert lines and all(line.startswith("forensics: error: ") for line in lines)
    assert any(line.startswith(f"forensics: error: {name}: ") for line in lines), out.stderr
    assert "Traceback" not in out.stderr


def test_flipped_evidence_fails_and_is_named(bundle, data_dir, tmp_path):
    photo = tmp_path / "Canon_40D.jpg"
    shutil.copyfile(data_dir / "exif" / "Canon_40D.jpg", photo)
    flip_byte(photo, 0.9)
    out = run("verify", bundle, "--evidence", photo)
    assert out.returncode == 1
    assert out.stderr.strip() == ("forensics: error: evidence: Canon_40D.jpg does not match the SHA-256/SHA-512 "
                                  "recorded for Canon_40D.jpg")


def test_bytes_appended_to_the_pdf_fail(bundle_copy):
    with (bundle_copy / "report.pdf").open("ab") as fh:
        fh.write(b"\n% appended after %%EOF\n")
    result = verify_bundle(bundle_copy)
    assert "report.pdf: PDF signature does not cover the entire file (coverage ENTIRE_REVISION; bytes were added " \
           "after signing)" in failures(result)
    assert any(p.startswith("report.pdf: has ") and p.endswith("the manifest records (altered)")
               for p in failures(result))


def test_an_extra_or_missing_file_fails(bundle_copy):
    (bundle_copy / "notes.txt").write_text("added later")
    (bundle_copy / "report.html").unlink()
    got = failures(verify_bundle(bundle_copy))
    assert "notes.txt: not listed in the manifest" in got and "report.html: missing" in got


def test_another_trust_anchor_fails(bundle, tmp_path, key):
    p12, cert = signing.create_self_signed("Someone Else", "Elsewhere")
    _, pem = signing.write_key_files(tmp_path, p12, cert)
    trust.remove(key.fingerprint)
    got = failures(verify_bundle(bundle, trust=pem))
    assert got == [f"signer: signatures valid but signer not trusted: Organization: Forensic Lab <Test>, Common Name: "
                   f"Dr. Ada Examiner, SHA-256 {key.fingerprint}"]


def test_pdf_is_a_pades_certification_with_no_changes_permitted(bundle, key):
    from pyhanko.pdf_utils.reader import PdfFileReader
    from pyhanko.sign.fields import MDPPerm
    from pyhanko.sign.validation.pdf_embedded import read_certification_data

    reader = PdfFileReader(BytesIO((bundle / "report.pdf").read_bytes()))
    assert read_certification_data(reader).permission is MDPPerm.NO_CHANGES
    (sig,) = reader.embedded_signatures
    assert sig.sig_object["/SubFilter"] == "/ETSI.CAdES.detached"
    assert sig.signer_cert.sha256_fingerprint.replace(" ", "").upper() == key.fingerprint.replace(":", "")


def test_pdfsig_reports_the_signature_valid_and_total(bundle, tmp_path):
    out = subprocess.run(["pdfsig", str(bundle / "report.pdf")], capture_output=True, text=True)
    assert "Signature Validation: Signature is Valid." in out.stdout, out.stdout
    assert "Total document signed" in out.stdout and "Not total document signed" not in out.stdout
    assert "Signer Certificate Common Name: Dr. Ada Examiner" in out.stdout
    appended = tmp_path / "appended.pdf"
    appended.write_bytes((bundle / "report.pdf").read_bytes() + b"\nextra")
    assert "Not total document signed" in subprocess.run(["pdfsig", str(appended)], capture_output=True,
                                                         text=True).stdout


def test_openssl_verifies_the_manifest_signature(bundle_copy, key_files):
    cmd = ["openssl", "cms", "-verify", "-binary", "-inform", "DER", "-in", str(bundle_copy / SIGNATURE_NAME),
           "-content", str(bundle_copy / MANIFEST_NAME), "-CAfile", str(key_files[1]), "-out", "/dev/null"]
    ok = subprocess.run(cmd, capture_output=True, text=True)
    assert ok.returncode == 0 and "Verification successful" in ok.stderr, ok.stderr
    flip_byte(bundle_copy / MANIFEST_NAME)
    bad = subprocess.run(cmd, capture_output=True, text=True)
    assert bad.returncode != 0 and "Verification failure" in bad.stderr


def test_keys_create_makes_a_usable_protected_key(tmp_path, data_dir):
    env = {"FORENSICS_KEY_PASSWORD": "correct horse"}
    out = run("keys", "create", "--name", "Dr. Ada Examiner", "--org", "Lab", "--out", tmp_path / "k", env=env)
    assert out.returncode == 0, out.stderr
    p12 = tmp_path / "k" / "examiner.p12"
    assert p12.stat().st_mode & 0o077 == 0
    assert "SHA-256:" in out.stdout and "self-signed" in out.stdout and "trusted:     yes" in out.stdout
    with pytest.raises(signing.SigningError, match="wrong password"):
        signing.load_key(p12, b"wrong")
    again = run("keys", "create", "--name", "X", "--org", "Y", "--out", tmp_path / "k", env=env)
    assert again.returncode == 1 and "refusing to overwrite" in again.stderr

    analysed = run("analyze", data_dir / "exif" / "Canon_40D.jpg", "--out", tmp_path / "out", "--detectors", "",
                   "--key", p12, "--exhibit-id", "E-2", "--paper", "letter", env=env)
    assert analysed.returncode == 0, analysed.stderr
    folder = tmp_path / "out" / "Canon_40D"
    assert run("verify", folder).returncode == 0, "a key made by `keys create` is trusted"
    wrong = run("analyze", data_dir / "exif" / "Canon_40D.jpg", "--out", tmp_path / "out2", "--key", p12,
                env={"FORENSICS_KEY_PASSWORD": "nope"})
    assert wrong.returncode == 2 and "wrong password" in wrong.stderr and "Traceback" not in wrong.stderr


def test_rsa_3072_keys_sign_too(tmp_path, data_dir):
    p12, cert = signing.create_self_signed("RSA Examiner", "Lab", key_type="rsa-3072")
    p12_path, pem = signing.write_key_files(tmp_path / "k", p12, cert)
    assert cert.public_key().key_size == 3072
    folder = make_bundle(data_dir / "exif" / "Canon_40D.jpg", tmp_path / "b", signing.load_key(p12_path, None))
    assert verify_bundle(folder, trust=pem).ok
    out = subprocess.run(["pdfsig", str(folder / "report.pdf")], capture_output=True, text=True)
    assert "Signature is Valid." in out.stdout


def test_ed25519_keys_are_refused(tmp_path):
    from datetime import datetime, timedelta, timezone

    from cryptography import x509
    from cryptography.x509.oid import NameOID

    key = ed25519.Ed25519PrivateKey.generate()
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "ed")])
    now = datetime.now(timezone.utc)
    cert = (x509.CertificateBuilder().subject_name(name).issuer_name(name).public_key(key.public_key())
            .serial_number(1).not_valid_before(now).not_valid_after(now + timedelta(days=1)).sign(key, None))
    path = tmp_path / "ed.p12"
    path.write_bytes(pkcs12.serialize_key_and_certificates(b"ed", key, cert, None, NoEncryption()))
    with pytest.raises(signing.SigningError, match="poppler rejects Ed25519"):
        signing.load_key(path, None)


def test_per_user_key_is_made_on_first_use_and_reused(tmp_path, data_dir, isolated_home):
    photo = data_dir / "exif" / "Canon_40D.jpg"
    first = run("analyze", photo, "--out", tmp_path / "a", "--detectors", "", "--examiner", "Dr. B")
    assert first.returncode == 0, first.stderr
    assert "made a self-signed examiner key for trial use" in first.stdout
    assert (isolated_home / "examiner.p12").is_file() and (isolated_home / "examiner.pem").is_file()
    second = run("analyze", photo, "--out", tmp_path / "b", "--detectors", "")
    assert second.returncode == 0 and "made a self-signed" not in second.stdout
    fp = [json.loads((tmp_path / d / "Canon_40D" / MANIFEST_NAME).read_text())["signer"]["sha256_fingerprint"]
          for d in ("a", "b")]
    assert fp[0] == fp[1]
    text = " ".join(" ".join(pdf_pages_text(tmp_path / "a" / "Canon_40D" / "report.pdf")).split())
    assert "This certificate is self-signed" in text and "CN=Dr. B" in text


def test_a_certificate_file_lost_with_a_stopped_first_run_is_written_again(isolated_home):
    # The first run is stopped after storing the key, before the certificate
    # beside it: the next run writes the key's own certificate there.
    made = signing.default_key("Dr. B")
    (isolated_home / "examiner.pem").unlink()
    again = signing.default_key()
    assert again.fingerprint == made.fingerprint
    assert (isolated_home / "examiner.pem").read_bytes() == made.cert_pem


def test_runs_started_together_on_a_fresh_home_make_one_key_and_all_sign_with_it(tmp_path, data_dir, monkeypatch):
    # Newsrooms start runs over folders of photos in parallel; on a fresh
    # account they all reach first-use key creation at once. A few rounds,
    # since each round is one chance for the processes to interleave.
    photo = data_dir / "exif" / "Canon_40D.jpg"
    runs = 4
    for round_ in range(2):
        home = tmp_path / f"home{round_}"
        monkeypatch.setenv("FORENSICS_HOME", str(home))
        outs = [tmp_path / f"out{round_}-{i}" for i in range(runs)]
        analyses = [subprocess.Popen([*FORENSICS, "analyze", str(photo), "--out", str(out), "--detectors", "",
                                      "--format", "html", "--isolation", "inline", "--jobs", "1"],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                    for out in outs]
        results = [p.communicate(timeout=120) for p in analyses]
        assert [p.returncode for p in analyses] == [0] * runs, [stderr for _, stderr in results]
        assert sum("made a self-signed examiner key" in stdout for stdout, _ in results) == 1

        assert sorted(p.name for p in home.iterdir()) == ["examiner.p12", "examiner.pem", "trusted"]
        assert (home / "examiner.p12").stat().st_mode & 0o077 == 0
        key = signing.load_key(home / "examiner.p12", None)
        assert (home / "examiner.pem").read_bytes() == key.cert_pem, "the certificate file is the key's own"
        assert [t.fingerprint for t in trust.trusted()] == [key.fingerprint], "only the key in use is trusted"

        checks = [subprocess.Popen([*FORENSICS, "verify", str(out / "Canon_40D")],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for out in outs]
        for out, check in zip(outs, checks):
            stdout, stderr = check.communicate(timeout=120)
            assert check.returncode == 0, stderr
            assert f"SHA-256 {key.fingerprint}, trusted" in stdout, "the bundle was signed by the one key"
            assert (out / "Canon_40D" / "signer.pem").read_bytes() == key.cert_pem


def test_xdg_config_home_is_honoured(tmp_path, data_dir, monkeypatch):
    monkeypatch.delenv("FORENSICS_HOME")
    xdg = tmp_path / "xdg"
    out = run("analyze", data_dir / "exif" / "Canon_40D.jpg", "--out", tmp_path / "o", "--detectors", "",
              "--format", "html", env={"XDG_CONFIG_HOME": str(xdg)})
    assert out.returncode == 0, out.stderr
    assert (xdg / "forensics" / "examiner.p12").is_file()
    folder = tmp_path / "o" / "Canon_40D"
    assert not (folder / "report.pdf").exists() and (folder / "report.html").exists()
    assert (xdg / "forensics" / "trusted").is_dir()
    assert run("verify", folder, env={"XDG_CONFIG_HOME": str(xdg)}).returncode == 0


def test_json_only_needs_no_key(tmp_path, data_dir, isolated_home):
    out = run("analyze", data_dir / "exif" / "Canon_40D.jpg", "--out", tmp_path / "o", "--format", "json",
              "--detectors", "")
    assert out.returncode == 0
    assert sorted(p.name for p in (tmp_path / "o" / "Canon_40D").iterdir()) == ["findings.json"]
    assert not (isolated_home / "examiner.p12").exists()


@pytest.mark.parametrize("kind", ["fifo", "device", "other_size"])
def test_verify_evidence_reads_only_a_regular_file_of_the_recorded_size(bundle, tmp_path, kind):
    import os

    if kind == "fifo":
        target = tmp_path / "evidence.jpg"
        os.mkfifo(target)
    elif kind == "device":
        target = Path("/dev/zero")
    else:
        target = tmp_path / "evidence.jpg"
        target.write_bytes(b"\xff" * 1000)
    out = run("verify", bundle, "--evidence", target)
    assert out.returncode == 1, out.stdout + out.stderr
    expected = "bytes, not the" if kind == "other_size" else "is not a regular file"
    assert expected in out.stdout + out.stderr and "Traceback" not in out.stderr


def test_a_manifest_nested_100000_deep_is_one_line(bundle_copy):
    from forensics_core.manifest import Manifest

    nested = b"[" * 100_000 + b"]" * 100_000
    with pytest.raises(ValueError, match="nested too deeply"):
        Manifest.from_bytes(nested)
    (bundle_copy / MANIFEST_NAME).write_bytes(nested)
    out = run("verify", bundle_copy)
    assert out.returncode == 1
    assert "RecursionError" not in out.stdout + out.stderr and "internal error" not in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1, out.stderr


def test_without_a_named_examiner_the_report_says_so_instead_of_a_login(tmp_path, data_dir, isolated_home):
    photo = data_dir / "exif" / "Canon_40D.jpg"
    out = run("analyze", photo, "--out", tmp_path / "a", "--detectors", "", "--format", "html")
    assert out.returncode == 0, out.stderr
    html = (tmp_path / "a" / "Canon_40D" / "report.html").read_text(encoding="utf-8")
    assert "not named: the signing key names no examiner" in html
    cert = (isolated_home / "examiner.pem").read_text()
    from cryptography import x509

    subject = x509.load_pem_x509_certificate(cert.encode()).subject.rfc4514_string()
    assert "CN=unnamed examiner" in subject and "CN=root" not in subject


def test_verify_prints_one_line_per_failure_and_no_library_traceback(bundle_copy, tmp_path, key):
    from pyhanko.pdf_utils import generic
    from pyhanko.pdf_utils.incremental_writer import IncrementalPdfFileWriter

    other = tmp_path / "other.pem"
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", str(tmp_path / "k.pem"),
                    "-out", str(other), "-subj", "/CN=other", "-days", "2"], check=True, capture_output=True)
    trust.remove(key.fingerprint)
    untrusted = run("verify", bundle_copy, "--trust", other)
    assert untrusted.returncode == 1 and "Traceback" not in untrusted.stderr
    assert untrusted.stderr.strip().splitlines() == [
        f"forensics: error: signer: signatures valid but signer not trusted: Organization: Forensic Lab <Test>, "
        f"Common Name: Dr. Ada Examiner, SHA-256 {key.fingerprint}"]
    pdf = bundle_copy / "report.pdf"
    writer = IncrementalPdfFileWriter(BytesIO(pdf.read_bytes()))
    writer.root["/Lang"] = generic.TextStringObject("fr")
    writer.update_root()
    out = BytesIO()
    writer.write(out)
    pdf.write_bytes(out.getvalue())
    updated = run("verify", bundle_copy)
    assert updated.returncode == 1 and "Traceback" not in updated.stderr
    assert all(line.startswith("forensics: error: ") for line in updated.stderr.strip().splitlines())
    assert "log:" in run("verify", bundle_copy, "--verbose").stderr


def test_a_manifest_describing_another_signer_than_its_certificate_fails(bundle_copy, key):
    manifest = json.loads((bundle_copy / MANIFEST_NAME).read_text())
    manifest["signer"]["subject"] = "CN=Prof. Someone Else\u202eegduj"
    manifest["signer"]["self_signed"] = False
    data = json.dumps(manifest, indent=2).encode()
    (bundle_copy / MANIFEST_NAME).write_bytes(data)
    (bundle_copy / SIGNATURE_NAME).write_bytes(signing.sign_detached(data, key))
    result = verify_bundle(bundle_copy)
    assert any("describes its signer as 'CN=Prof. Someone Else\\u202eegduj'" in p and "Dr. Ada Examiner" in p
               for p in failures(result))
    assert not any("Someone" in note for note in result.notes)
    assert any("self-signed (" in note and "CN=Dr. Ada Examiner" in note for note in result.notes)
