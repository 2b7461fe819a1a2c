"""What counts as finished, what a killed run leaves behind, the lock."""

import json
import os
import tempfile

import pytest

from forensics_core.batch.resume import (Expected, LockHeld, OutputLock, is_complete, link_folder, recorded_sha,
                                         remove_temp_files)
from forensics_core.manifest import sha256_file

SHA = "ab" * 32
PARAMS = {"detectors": ["steady"], "detector_params": {"steady": {"seconds": 0.0}}}


def _bundle(folder, formats=("html",), exhibit=None):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "findings.json").write_text(json.dumps({"evidence": {"sha256": SHA}, "parameters": PARAMS}))
    names = ["findings.json"]
    if "html" in formats:
        (folder / "report.html").write_text("<html></html>")
        names.append("report.html")
    files = [{"name": n, "size": (folder / n).stat().st_size, "sha256": sha256_file(folder / n)} for n in names]
    manifest = {"manifest_version": "1", "evidence": {"sha256": SHA}, "exhibit_id": exhibit, "files": files}
    (folder / "manifest.json").write_text(json.dumps(manifest))
    (folder / "manifest.json.p7s").write_bytes(b"signature")
    return folder


def test_json_only_needs_findings_of_the_photo_with_the_same_settings(tmp_path):
    folder = _bundle(tmp_path / "x", formats=())
    assert is_complete(folder, SHA, Expected((), PARAMS, None))
    assert not is_complete(folder, "cd" * 32, Expected((), PARAMS, None))
    assert not is_complete(folder, SHA, Expected((), {**PARAMS, "detectors": ["steady", "cfa"]}, None))
    assert not is_complete(tmp_path / "missing", SHA, Expected((), PARAMS, None))


def test_reports_need_the_signature_written_last_and_files_matching_the_manifest(tmp_path):
    expected = Expected(("html",), PARAMS, "EX-1")
    folder = _bundle(tmp_path / "x", exhibit="EX-1")
    assert is_complete(folder, SHA, expected)
    assert not is_complete(folder, SHA, Expected(("html", "pdf"), PARAMS, "EX-1"))  # no report.pdf listed
    assert not is_complete(folder, SHA, Expected(("html",), PARAMS, "EX-2"))
    (folder / "report.html").write_text("<html>cut</html")
    assert not is_complete(folder, SHA, expected)
    folder = _bundle(tmp_path / "y", exhibit="EX-1")
    doc = json.loads((folder / "findings.json").read_text())
    (folder / "findings.json").write_text(json.dumps(doc, indent=1))  # rewritten by a later run
    assert not is_complete(folder, SHA, expected)


def test_leftovers_of_a_killed_run_are_removed_and_nothing_else(tmp_path):
    fd, tmp = tempfile.mkstemp(prefix=".findings.json.", suffix=".tmp", dir=tmp_path)  # as write_atomic names them
    os.close(fd)
    stale_dir = tempfile.mkdtemp(prefix=".x.", suffix=".tmp", dir=tmp_path)
    for keep in ("notes.tmp", ".hidden", "findings.json"):
        (tmp_path / keep).write_text("keep")
    assert recorded_sha(tmp_path / "nothing") is None
    assert remove_temp_files(tmp_path) == 2
    assert not os.path.exists(tmp) and not os.path.exists(stale_dir)
    assert sorted(p.name for p in tmp_path.iterdir()) == [".hidden", "findings.json", "notes.tmp"]


def test_folders_owned_free_or_foreign(tmp_path):
    _bundle(tmp_path / "mine")
    assert recorded_sha(tmp_path / "mine") == SHA
    (tmp_path / "leftover").mkdir()
    (tmp_path / "leftover" / ".findings.json.abcd_123.tmp").write_text("")
    assert recorded_sha(tmp_path / "leftover") is None
    (tmp_path / "theirs").mkdir()
    (tmp_path / "theirs" / "a.txt").write_text("")
    (tmp_path / "file").write_text("")
    assert recorded_sha(tmp_path / "theirs") == "foreign" and recorded_sha(tmp_path / "file") == "foreign"


def test_duplicate_links_are_relative_and_replace_an_unfinished_folder(tmp_path):
    _bundle(tmp_path / "x")
    (tmp_path / "copy").mkdir()
    (tmp_path / "copy" / "findings.json").write_text("{}")
    link_folder(tmp_path, "copy", "x")
    assert os.readlink(tmp_path / "copy") == "x"
    assert recorded_sha(tmp_path / "copy") == SHA
    link_folder(tmp_path, "copy", "x")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["copy", "x"]


def test_one_batch_at_a_time_per_output_folder(tmp_path):
    with OutputLock(tmp_path):
        with pytest.raises(LockHeld, match="another `forensics batch`"):
            OutputLock(tmp_path).__enter__()
    with OutputLock(tmp_path):
        pass
