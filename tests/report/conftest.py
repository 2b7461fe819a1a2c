"""Fixtures of the report tests: an isolated key folder, a signing key, a signed bundle."""

import shutil
from pathlib import Path

import pytest

from forensics_core import signing, trust
from report_helpers import make_bundle


@pytest.fixture(autouse=True)
def isolated_home(tmp_path, monkeypatch, key_files):
    """Keys made on first use go to a folder of this test, never the user's; its trust store holds the test key."""
    home = tmp_path / "forensics-home"
    monkeypatch.setenv("FORENSICS_HOME", str(home))
    monkeypatch.delenv("FORENSICS_KEY_PASSWORD", raising=False)
    trust.add(key_files[1])
    return home


@pytest.fixture(scope="session")
def key_files(tmp_path_factory) -> tuple[Path, Path]:
    """A self-signed ECDSA P-256 examiner key without password: (p12, pem)."""
    folder = tmp_path_factory.mktemp("key")
    p12, cert = signing.create_self_signed("Dr. Ada Examiner", "Forensic Lab <Test>")
    return signing.write_key_files(folder, p12, cert)


@pytest.fixture(scope="session")
def key(key_files) -> signing.ExaminerKey:
    return signing.load_key(key_files[0], None)


@pytest.fixture(scope="session")
def bundle(tmp_path_factory, key, data_dir) -> Path:
    """A complete signed bundle of the Canon 40D sample (it has a thumbnail and GPS), never modified."""
    return make_bundle(data_dir / "exif" / "Canon_40D.jpg", tmp_path_factory.mktemp("bundle") / "Canon_40D", key)


@pytest.fixture
def bundle_copy(bundle, tmp_path) -> Path:
    target = tmp_path / "copy"
    shutil.copytree(bundle, target)
    return target
