"""Reading suites: the truth file, the authentic/tampered layout, and refusals."""

import numpy as np
import pytest
from PIL import Image

from forensics_core.validation import SuiteError, folder_suite


def photo(path, value=100, size=(16, 12)):
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.full(size[::-1], value, np.uint8)).save(path)
    return path


def test_truth_file_with_masks_and_condition_columns(tmp_path):
    photo(tmp_path / "p" / "a.png")
    photo(tmp_path / "p" / "b.png", 120)
    photo(tmp_path / "m" / "b.png", 255)
    (tmp_path / "truth.csv").write_text("file,label,mask,jpeg_quality,kind\n"
                                        "p/a.png,authentic,,90,\n"
                                        "p/b.png,Tampered,m/b.png,75,copy_move\n")
    suite = folder_suite(tmp_path)
    a, b = suite.cases
    assert (a.spliced, a.mask, dict(a.conditions)) == (False, None, {"jpeg_quality": "90"})
    assert (b.spliced, b.mask.name, dict(b.conditions)) == (True, "b.png", {"jpeg_quality": "75", "kind": "copy_move"})
    assert len(suite.content_sha256) == 64


def test_content_hash_changes_with_a_label(tmp_path):
    photo(tmp_path / "a.png")
    (tmp_path / "truth.csv").write_text("file,label\na.png,authentic\n")
    first = folder_suite(tmp_path).content_sha256
    (tmp_path / "truth.csv").write_text("file,label\na.png,spliced\n")
    assert folder_suite(tmp_path).content_sha256 != first


def test_common_public_layout_with_masks_matched_by_stem(tmp_path):
    photo(tmp_path / "Au" / "Au_ani_1.jpg")
    photo(tmp_path / "Tp" / "Tp_S_1.jpg")
    photo(tmp_path / "Tp" / "Tp_S_2.tif")
    photo(tmp_path / "Groundtruth" / "Tp_S_1_gt.png", 255)
    cases = {c.name: c for c in folder_suite(tmp_path).cases}
    assert set(cases) == {"au_Au_ani_1", "tp_Tp_S_1", "tp_Tp_S_2"}
    assert cases["tp_Tp_S_1"].mask.name == "Tp_S_1_gt.png"
    assert cases["tp_Tp_S_2"].mask is None and cases["tp_Tp_S_2"].spliced


@pytest.mark.parametrize("truth, message", [
    ("name,label\n", "at least the columns file and label"),
    ("file,label\n../outside.png,spliced\n", "outside the suite folder"),
    ("file,label\nmissing.png,spliced\n", "no file 'missing.png'"),
    ("file,label\na.png,maybe\n", "neither spliced nor authentic"),
    ("file,label\na\0.png,spliced\n", "line 2: 'a\\\\x00.png' holds a NUL byte"),
    (b"file,label\na.png,authentic\ncaf\xe9.png,spliced\n", "truth.csv: not UTF-8 text"),
])
def test_bad_truth_files_are_refused_with_the_line(tmp_path, truth, message):
    photo(tmp_path / "a.png")
    photo(tmp_path.parent / "outside.png")
    (tmp_path / "truth.csv").write_bytes(truth if isinstance(truth, bytes) else truth.encode())
    with pytest.raises(SuiteError, match=message):
        folder_suite(tmp_path)


def test_a_folder_without_truth_or_layout_is_refused(tmp_path):
    photo(tmp_path / "x.png")
    with pytest.raises(SuiteError, match="no truth.csv and no authentic/ and tampered/"):
        folder_suite(tmp_path)
