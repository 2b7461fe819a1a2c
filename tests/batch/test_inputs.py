"""Finding and hashing the photos of a batch."""

import hashlib
import os

import pytest

from forensics_core.batch.inputs import discover, hash_all, sha256_of


def _tree(root):
    for rel in ("a.jpg", "z.txt", ".hidden.jpg", "sub/b.jpg", "sub/.c.jpg", ".git/d.jpg", "out/report.png"):
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(rel.encode())


def test_folders_give_their_children_or_with_recursive_all_descendants(tmp_path):
    root = tmp_path / "in"
    _tree(root)
    out = root / "out"
    assert [p for p, _ in discover([root], out)] == [root / "a.jpg", root / "z.txt"]
    found = [p.relative_to(root).as_posix() for p, _ in discover([root], out, recursive=True)]
    # Hidden files and folders and the output folder (a rerun's own reports) are left out.
    assert found == ["a.jpg", "z.txt", "sub/b.jpg"]
    inner = tmp_path / "o" / "photos"  # e.g. `batch photos --out .`: the photos are still read
    inner.mkdir(parents=True)
    (inner / "p.jpg").write_bytes(b"p")
    assert [p for p, _ in discover([inner], tmp_path / "o")] == [inner / "p.jpg"]


def test_named_files_are_taken_as_given_once_each_and_missing_ones_carry_a_reason(tmp_path):
    root = tmp_path / "in"
    _tree(root)
    found = discover([root / ".hidden.jpg", root, root / "a.jpg", tmp_path / "nope.jpg"], tmp_path / "out")
    assert found == [(root / ".hidden.jpg", None), (root / "a.jpg", None), (root / "z.txt", None),
                     (tmp_path / "nope.jpg", "no such file or folder")]


def test_hashes_match_hashlib_and_unreadable_inputs_say_why(tmp_path):
    photo = tmp_path / "p.jpg"
    photo.write_bytes(b"\xff\xd8" + bytes(range(256)) * 5000)
    assert sha256_of(photo).sha256 == hashlib.sha256(photo.read_bytes()).hexdigest()
    assert sha256_of(tmp_path).error == "is a directory, not a photo"
    assert sha256_of(tmp_path / "missing").error == "no such file"
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    assert sha256_of(fifo).error == "is not a regular file"  # reading it would block for ever
    photos = list(hash_all([(photo, None), (tmp_path / "x", "no such file or folder")]))
    assert [p.path for p in photos] == [photo, tmp_path / "x"]
    assert photos[1].error == "no such file or folder" and photos[1].sha256 is None


@pytest.mark.parametrize("recursive", [False, True])
def test_fifos_and_links_to_devices_in_a_folder_are_listed_not_skipped(tmp_path, recursive):

    (tmp_path / "a.jpg").write_bytes(b"\xff\xd8")
    os.mkfifo(tmp_path / "pipe.jpg")
    (tmp_path / "zero.jpg").symlink_to("/dev/zero")
    (tmp_path / "broken.jpg").symlink_to(tmp_path / "nowhere")
    found = {p.name for p, _ in discover([tmp_path], tmp_path / "out", recursive)}
    assert found == {"a.jpg", "pipe.jpg", "zero.jpg", "broken.jpg"}
    errors = {p.name: sha256_of(p).error for p, _ in discover([tmp_path], tmp_path / "out", recursive)}
    assert errors["pipe.jpg"] == errors["zero.jpg"] == "is not a regular file"
    assert errors["broken.jpg"] == "no such file" and errors["a.jpg"] is None


@pytest.mark.parametrize("recursive", [False, True])
def test_links_that_loop_are_listed_as_failed_and_hide_no_other_photo(tmp_path, recursive):
    # Following them fails (ELOOP) and resolving them raised: the whole folder
    # used to be read as empty, or the batch stopped.
    (tmp_path / "a.jpg").write_bytes(b"\xff\xd8")
    (tmp_path / "loop1.jpg").symlink_to(tmp_path / "loop2.jpg")
    (tmp_path / "loop2.jpg").symlink_to(tmp_path / "loop1.jpg")
    found = discover([tmp_path], tmp_path / "out", recursive)
    assert {p.name for p, _ in found} == {"a.jpg", "loop1.jpg", "loop2.jpg"}
    errors = {p.name: sha256_of(p).error for p, _ in found}
    assert errors["a.jpg"] is None
    assert errors["loop1.jpg"].startswith("cannot read: ") and errors["loop2.jpg"].startswith("cannot read: ")
    assert [p.name for p, _ in discover([tmp_path / "loop1.jpg"], tmp_path / "out")] == ["loop1.jpg"]
