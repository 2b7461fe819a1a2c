"""provenance on photos the tests sign themselves, with a certificate chain made here (no network)."""

import datetime
import io
import json
import os
import time

import c2pa
import numpy as np
import pytest
from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID
from PIL import Image

from forensics_core import Status, load_evidence
from forensics_plugins.provenance.detector import Provenance
from forensics_plugins.provenance.spec import DEFAULT_PARAMS

CAPTURE = "http://cv.iptc.org/newscodes/digitalsourcetype/digitalCapture"
GENERATED = "http://cv.iptc.org/newscodes/digitalsourcetype/trainedAlgorithmicMedia"


def _name(cn):
    return x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, cn), x509.NameAttribute(NameOID.ORGANIZATION_NAME, "Tests")])


def _usage(**set_):
    flags = dict.fromkeys(("digital_signature", "content_commitment", "key_encipherment", "data_encipherment",
                           "key_agreement", "key_cert_sign", "crl_sign", "encipher_only", "decipher_only"), False)
    return x509.KeyUsage(**{**flags, **set_})


def _make_chain(valid_for: datetime.timedelta) -> dict:
    """A root and a signing certificate valid from a day ago for ``valid_for`` more (the root for 30 days)."""
    now = datetime.datetime.now(datetime.timezone.utc)
    root_key, key = ec.generate_private_key(ec.SECP256R1()), ec.generate_private_key(ec.SECP256R1())

    def cert(subject, issuer, public, signing_key, serial, ca, until):
        b = (x509.CertificateBuilder().subject_name(subject).issuer_name(issuer).public_key(public)
             .serial_number(serial).not_valid_before(now - datetime.timedelta(days=1))
             .not_valid_after(until)
             .add_extension(x509.BasicConstraints(ca=ca, path_length=None), critical=True)
             .add_extension(_usage(key_cert_sign=True, crl_sign=True) if ca else _usage(digital_signature=True),
                            critical=True)
             .add_extension(x509.SubjectKeyIdentifier.from_public_key(public), critical=False))
        if not ca:
            b = (b.add_extension(x509.ExtendedKeyUsage([ExtendedKeyUsageOID.EMAIL_PROTECTION]), critical=False)
                 .add_extension(x509.AuthorityKeyIdentifier.from_issuer_public_key(signing_key.public_key()),
                                critical=False))
        return b.sign(signing_key, hashes.SHA256())

    root = cert(_name("Tests Root CA"), _name("Tests Root CA"), root_key.public_key(), root_key, 1, True,
                now + datetime.timedelta(days=30))
    leaf = cert(_name("Tests Camera"), root.subject, key.public_key(), root_key, 2, False, now + valid_for)
    pem = serialization.Encoding.PEM
    return {"chain": leaf.public_bytes(pem) + root.public_bytes(pem), "root": root.public_bytes(pem).decode(),
            "key": key.private_bytes(pem, serialization.PrivateFormat.PKCS8, serialization.NoEncryption())}


@pytest.fixture(scope="module")
def chain():
    return _make_chain(datetime.timedelta(days=30))


def _photo() -> bytes:
    buf = io.BytesIO()
    Image.fromarray((np.random.default_rng(0).random((96, 128, 3)) * 255).astype(np.uint8)).save(buf, "JPEG", quality=90)
    return buf.getvalue()


def _sign(chain, actions, embed=True, parent: bytes | None = None) -> tuple[bytes, bytes]:
    """A photo signed with ``actions``, or, with ``parent``, as an edit of that signed photo."""
    signer = c2pa.Signer.from_info(c2pa.C2paSignerInfo(c2pa.C2paSigningAlg.ES256, chain["chain"], chain["key"], None))
    manifest = {"claim_generator_info": [{"name": "forensics-tests", "version": "1"}], "title": "photo.jpg",
                "assertions": [{"label": "c2pa.actions", "data": {"actions": actions}}] if actions else []}
    builder = c2pa.Builder(json.dumps(manifest))
    if parent is not None:
        builder.set_intent(c2pa.C2paBuilderIntent.EDIT)
        builder.add_ingredient(json.dumps({"title": "parent.jpg", "relationship": "parentOf"}), "image/jpeg",
                               io.BytesIO(parent))
    if not embed:
        builder.set_no_embed()
    out = io.BytesIO()
    store = builder.sign(signer, "image/jpeg", io.BytesIO(_photo()), out)
    return out.getvalue(), store


def _finding(tmp_path, data, name="photo.jpg", **params):
    path = tmp_path / name
    path.write_bytes(data)
    return Provenance().analyze(load_evidence(path), {**DEFAULT_PARAMS, **params})


def test_valid_credentials_of_a_capture(tmp_path, chain):
    signed, _ = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}])
    r = _finding(tmp_path, signed)
    assert r.status is Status.OK and r.score == 0.0 and r.p_value is None
    cred = r.details["credentials"]
    assert cred["state"] == "Valid" and not cred["binding_broken"]
    assert cred["signer"]["common_name"] == "Tests Camera" and "forensics-tests 1" in cred["claim_generator"]
    assert "not checked against a trust list" in r.summary and "does not show that the scene was real" in r.summary


def test_trust_anchors_make_the_signer_trusted(tmp_path, chain):
    signed, _ = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}])
    (tmp_path / "anchors.pem").write_text(chain["root"])
    r = _finding(tmp_path, signed, trust_anchors_file=str(tmp_path / "anchors.pem"))
    assert r.details["credentials"]["state"] == "Trusted" and "on the examiner's trust list" in r.summary


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_trust_anchors_file_that_is_no_regular_file_is_refused_at_once(tmp_path, chain, kind):
    signed, _ = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}])
    anchors = tmp_path / "anchors.pem"
    if kind == "fifo":
        os.mkfifo(anchors)
    else:
        anchors.symlink_to("/dev/zero")
    with pytest.raises(ValueError, match="trust anchors file cannot be used: .* not a regular file"):
        _finding(tmp_path, signed, trust_anchors_file=str(anchors))


def test_content_changed_after_signing_breaks_the_binding(tmp_path, chain):
    signed, _ = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}])
    tampered = bytearray(signed)
    tampered[-300] ^= 0x5A
    r = _finding(tmp_path, bytes(tampered))
    assert r.status is Status.OK and r.score == 1.0
    cred = r.details["credentials"]
    assert cred["state"] == "Invalid" and cred["binding_broken"]
    assert "assertion.dataHash.mismatch" in {f["code"] for f in cred["failures"]}
    assert "changed after it was signed" in r.summary and not r.summary.startswith("Valid")


def test_an_expired_signing_credential_is_never_called_valid(tmp_path):
    # The SDK calls these credentials Invalid (signingCredential.expired) although the binding holds.
    signed, _ = _sign(_make_chain(datetime.timedelta(seconds=1)),
                      [{"action": "c2pa.created", "digitalSourceType": CAPTURE}])
    time.sleep(2.5)
    r = _finding(tmp_path, signed)
    cred = r.details["credentials"]
    assert cred["state"] == "Invalid" and cred["credential_failures"] == ["signingCredential.expired"]
    assert not cred["binding_broken"] and not cred["integrity_broken"]
    assert r.status is Status.INCONCLUSIVE and r.score is None
    assert "Valid Content Credentials" not in r.summary and "signingCredential.expired" in r.summary
    assert "no evidence that the content changed" in r.summary


def test_an_ingredient_whose_own_signature_fails_is_named(tmp_path, chain):
    parent, _ = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}])
    at = parent.find(b"c2pa.signature") + 600
    forged = parent[:at] + bytes([parent[at] ^ 0x01]) + parent[at + 1:]
    edit, _ = _sign(chain, [], parent=forged)
    r = _finding(tmp_path, edit)
    assert r.details["credentials"]["state"] == "Valid" and r.status is Status.OK
    (bad,) = r.details["credentials"]["ingredient_failures"]
    assert "claimSignature.mismatch" in bad["codes"]
    assert "ingredient(s) carry credentials that fail validation (claimSignature.mismatch" in r.summary


def test_declared_edits_and_generative_source(tmp_path, chain):
    signed, _ = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": GENERATED},
                              {"action": "c2pa.edited", "softwareAgent": {"name": "Some Editor 2"}}])
    r = _finding(tmp_path, signed)
    assert r.score == 0.5 and r.details["edits"] == ["c2pa.edited"]
    assert r.details["credentials"]["source_types"] == ["trainedAlgorithmicMedia"]
    assert "generative source" in r.summary and "edits (c2pa.edited)" in r.summary


def test_no_credentials_is_inconclusive(tmp_path):
    r = _finding(tmp_path, _photo())
    assert r.status is Status.INCONCLUSIVE and r.score is None and "no Content Credentials" in r.summary


def test_a_sidecar_manifest_beside_the_photo(tmp_path, chain):
    signed, store = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}], embed=False)
    (tmp_path / "photo.c2pa").write_bytes(store)
    r = _finding(tmp_path, signed)
    assert r.status is Status.OK and r.details["credentials"]["sidecar"] and r.details["sidecar_sha256"]
    assert r.details["credentials"]["state"] == "Valid"


def test_a_broken_sidecar_never_hides_the_embedded_credentials(tmp_path, chain):
    signed, _ = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}])
    tampered = bytearray(signed)
    tampered[-300] ^= 0x5A
    (tmp_path / "photo.c2pa").write_bytes(b"x")
    r = _finding(tmp_path, bytes(tampered))
    assert r.status is Status.OK and r.score == 1.0 and r.details["credentials"]["binding_broken"]
    assert "changed after it was signed" in r.summary
    assert "The .c2pa file beside the photo cannot be read" in r.summary and r.details["sidecar_error"]

    (tmp_path / "plain.c2pa").write_bytes(b"x")
    r = _finding(tmp_path, _photo(), name="plain.jpg")
    assert r.status is Status.INCONCLUSIVE and "no Content Credentials" in r.summary
    assert "fault of that file, not of the photo" in r.summary


def test_a_sidecar_beside_embedded_credentials_is_validated_beside_them(tmp_path, chain):
    signed, _ = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}])
    _, store = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}], embed=False)
    (tmp_path / "photo.c2pa").write_bytes(store)
    r = _finding(tmp_path, signed)
    assert r.details["credentials"]["state"] == "Valid" and not r.details["credentials"]["sidecar"]
    assert r.details["sidecar_credentials"]["sidecar"]
    assert "holds another manifest store, which does not validate against the photo" in r.summary


def test_a_garbled_manifest_store_is_one_line(tmp_path, chain):
    signed, _ = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}])
    at = signed.find(b"c2pa.signature")
    garbled = signed[:at] + bytes(b ^ 0xFF for b in signed[at:at + 400]) + signed[at + 400:]
    r = _finding(tmp_path, garbled)
    assert r.status in (Status.OK, Status.INCONCLUSIVE)
    assert "\n" not in r.summary and (r.status is Status.INCONCLUSIVE or r.score == 1.0)


def test_through_the_entry_point_with_its_report_section(tmp_path, chain):
    from forensics_core.analysis import Options, analyze_evidence
    from forensics_core.plugins import PluginHost
    from forensics_core.report.plugin_sections import section_for

    host = PluginHost.from_entry_points(allow=["provenance"])
    signed, _ = _sign(chain, [{"action": "c2pa.created", "digitalSourceType": CAPTURE}])
    path = tmp_path / "signed.jpg"
    path.write_bytes(signed)
    ev = load_evidence(path)
    (finding,) = analyze_evidence(ev, host, Options(detectors=["provenance"], isolation="process")).detectors
    assert finding.status is Status.OK, finding.error or finding.summary
    body = str(section_for(host, finding, ev).body)
    for text in ("Tests Camera", "c2pa.created", "What this proves and what it does not", "honest", "offline"):
        assert text in body, text


def test_a_photo_without_credentials_gets_a_short_section_saying_where_they_were_looked_for(tmp_path):
    from forensics_core.analysis import Options, analyze_evidence
    from forensics_core.plugins import PluginHost
    from forensics_core.report.plugin_sections import section_for

    host = PluginHost.from_entry_points(allow=["provenance"])
    path = tmp_path / "plain.jpg"
    Image.new("RGB", (64, 48), (90, 120, 150)).save(path, quality=90)
    ev = load_evidence(path)
    (finding,) = analyze_evidence(ev, host, Options(detectors=["provenance"], isolation="inline")).detectors
    assert finding.status is Status.INCONCLUSIVE
    section = section_for(host, finding, ev)
    assert section.failure is None and section.title == "Content Credentials (C2PA)"
    body = str(section.body)
    assert "Looked in" in body and "Their absence says" in body and "sidecar_sha256" not in body
