"""Publishing a photo's bundle: one rename claims its folder, and a run that loses it places its bundle again."""

from pathlib import Path

from forensics_core.batch.resume import is_temp_name, remove_temp_files
from forensics_core.output import Placement, publish, staging_folder


def _bundle(folder: Path, text: str) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "findings.json").write_text(text)


def test_a_bundle_takes_an_absent_or_empty_folder_and_leaves_no_staging_folder(tmp_path):
    for name in ("absent", "empty"):
        target = tmp_path / name
        if name == "empty":
            target.mkdir()
        with staging_folder(target) as staging:
            assert is_temp_name(staging.name), "a killed run's staging folder must be one `forensics batch` removes"
            _bundle(staging, name)
            assert publish(staging, Placement(target), lambda: Placement(target, "kept")) == Placement(target)
        assert (target / "findings.json").read_text() == name
    assert sorted(p.name for p in tmp_path.iterdir()) == ["absent", "empty"]


def test_the_run_that_loses_the_folder_places_again_and_writes_nothing_into_the_winners_bundle(tmp_path):
    target, other = tmp_path / "photo", tmp_path / "photo-0123456789ab"
    with staging_folder(target) as staging:
        pass
    _bundle(staging, "second")
    _bundle(target, "first")  # the other run published while this one was writing
    again = [Placement(target, "kept"), Placement(other)]
    assert publish(staging, Placement(target), lambda: again[0]) == Placement(target, "kept")
    assert (target / "findings.json").read_text() == "first" and staging.is_dir()
    assert publish(staging, Placement(target), lambda: again[1]) == Placement(other)
    assert (target / "findings.json").read_text() == "first"
    assert (other / "findings.json").read_text() == "second" and not staging.exists()


def test_a_forced_replacement_swaps_the_whole_bundle_and_removes_the_old_one(tmp_path):
    target = tmp_path / "photo"
    _bundle(target, "old")
    (target / "report.pdf").write_text("old report")
    with staging_folder(target) as staging:
        _bundle(staging, "new")
    assert publish(staging, Placement(target, "replace"), lambda: Placement(target, "kept")).action == "replace"
    assert [p.name for p in target.iterdir()] == ["findings.json"]
    assert (target / "findings.json").read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["photo"]


def test_batch_removes_a_staging_folder_a_killed_run_left_but_not_one_in_use(tmp_path):
    with staging_folder(tmp_path / "photo") as staging:
        _bundle(staging, "under way")
        assert remove_temp_files(tmp_path) == 0 and (staging / "findings.json").exists()
    assert remove_temp_files(tmp_path) == 1 and not staging.exists()
