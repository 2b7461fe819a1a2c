"""Folder names, finished photos and duplicates: decided before any work, stable across reruns."""

import json

from forensics_core.batch.inputs import sha256_of
from forensics_core.batch.plan import make_plan
from forensics_core.batch.resume import Expected

EXPECTED = Expected((), {"detectors": ["steady"]}, None)


def _photo(root, rel, data: bytes):
    path = root / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)
    return sha256_of(path)


def _finish(folder, sha, detectors=("steady",)):
    folder.mkdir(parents=True, exist_ok=True)
    doc = {"evidence": {"sha256": sha}, "parameters": {"detectors": list(detectors)}}
    (folder / "findings.json").write_text(json.dumps(doc))


def _names(plan):
    return {p.path.relative_to(p.path.parents[1]).as_posix(): plan.entry_of[p.path].name
            for p in plan.photos if p.error is None}


def test_unique_stems_get_plain_folders_and_clashing_stems_the_hash_suffix(tmp_path):
    a = _photo(tmp_path, "a/x.jpg", b"one")
    b = _photo(tmp_path, "b/x.png", b"two")
    c = _photo(tmp_path, "b/y.jpg", b"three")
    plan = make_plan([b, c, a], tmp_path / "out", EXPECTED)
    assert _names(plan) == {"a/x.jpg": "x", "b/x.png": f"x-{b.sha256[:12]}", "b/y.jpg": "y"}
    assert [j.path for j in plan.jobs()] == [str(a.path), str(b.path), str(c.path)]


def test_names_do_not_move_when_a_clashing_photo_is_added_later(tmp_path):
    out = tmp_path / "out"
    b = _photo(tmp_path, "b/x.jpg", b"two")
    first = make_plan([b], out, EXPECTED)
    assert first.entry_of[b.path].name == "x"
    _finish(out / "x", b.sha256)
    a = _photo(tmp_path, "a/x.jpg", b"one")  # sorts first, but x is b's
    again = make_plan([a, b], out, EXPECTED)
    assert again.entry_of[b.path].name == "x" and again.entry_of[a.path].name == f"x-{a.sha256[:12]}"
    assert [j.path for j in again.jobs()] == [str(a.path)]


def test_a_folder_holding_something_else_is_never_written_into(tmp_path):
    out = tmp_path / "out"
    (out / "x").mkdir(parents=True)
    (out / "x" / "notes.txt").write_text("the examiner's own notes")
    (out / "summary").write_text("a file")
    x = _photo(tmp_path, "in/x.jpg", b"one")
    s = _photo(tmp_path, "in/summary.json.jpg", b"two")
    dots = _photo(tmp_path, "in/..jpg", b"three")
    plan = make_plan([x, s, dots], out, EXPECTED)
    assert plan.entry_of[x.path].name == f"x-{x.sha256[:12]}"
    assert plan.entry_of[s.path].name == f"summary.json-{s.sha256[:12]}"  # the summary's own name
    assert plan.entry_of[dots.path].name == f".-{dots.sha256[:12]}"  # never OUT/. itself


def test_duplicates_are_one_job_and_a_finished_folder_is_kept_as_the_primary(tmp_path):
    out = tmp_path / "out"
    a = _photo(tmp_path, "a/x.jpg", b"same")
    b = _photo(tmp_path, "b/x.jpg", b"same")
    c = _photo(tmp_path, "c/copy.jpg", b"same")
    plan = make_plan([a, b, c], out, EXPECTED)
    group = plan.groups[a.sha256]
    assert group.primary.paths == [a.path, b.path]  # same stem and bytes: one folder
    assert [e.name for e in group.others] == ["copy"]
    assert [j.path for j in plan.jobs()] == [str(a.path)]

    _finish(out / "copy", a.sha256)
    rerun = make_plan([a, b, c], out, EXPECTED)
    assert rerun.groups[a.sha256].primary.name == "copy" and not rerun.jobs()
    assert make_plan([a, b, c], out, EXPECTED, force=True).jobs()


def test_finished_with_other_settings_is_not_finished(tmp_path):
    out = tmp_path / "out"
    a = _photo(tmp_path, "a/x.jpg", b"one")
    _finish(out / "x", a.sha256, detectors=("lens_distortion",))
    plan = make_plan([a], out, EXPECTED)
    assert plan.entry_of[a.path].name == "x" and [j.folder for j in plan.jobs()] == [str(out / "x")]
