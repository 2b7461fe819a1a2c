import json
import shutil
from pathlib import Path

import jsonschema
import pytest

from forensics_core.findings import schema

DATA = Path(__file__).parent / "data"


@pytest.fixture(autouse=True)
def private_home(tmp_path_factory, monkeypatch):
    """Keep the per-user examiner key the CLI makes on first use, and the fingerprint cache, out of the real home."""
    monkeypatch.setenv("FORENSICS_HOME", str(tmp_path_factory.mktemp("forensics-home")))
    monkeypatch.setenv("FORENSICS_CACHE", str(tmp_path_factory.mktemp("forensics-cache")))


@pytest.fixture(scope="session")
def data_dir() -> Path:
    return DATA


@pytest.fixture
def photo(tmp_path) -> Path:
    """A real chessboard photo, copied so a test can watch its bytes."""
    target = tmp_path / "left01.jpg"
    shutil.copyfile(DATA / "calibration" / "left01.jpg", target)
    return target


@pytest.fixture(scope="session")
def validate():
    validator = jsonschema.Draft202012Validator(schema())

    def check(doc):
        if not isinstance(doc, dict):
            doc = json.loads(doc.to_json())
        validator.validate(doc)
        return doc

    return check
