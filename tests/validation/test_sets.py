"""Several sets in one run: reading them, the `set` condition, and conditions that name single photos."""

import numpy as np
import pytest
from PIL import Image

from forensics_core.findings import Status, VerdictLabel
from forensics_core.validation import SuiteError, read_suite
from forensics_core.validation.record import compute_methods
from forensics_core.validation.runner import CaseResult, DetectorOutcome


def photo(path, value=100, size=(16, 12)):
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.full(size[::-1], value, np.uint8)).save(path)
    return path


def truth_set(folder, rows):
    """A set folder: ``rows`` of (file, label, camera); each photo gets its own source."""
    for i, (name, _, _) in enumerate(rows):
        photo(folder / name, 60 + 10 * i)
    lines = [f"{f},{label},,repo@abc:{folder.name}/{f},{camera}" for f, label, camera in rows]
    (folder / "truth.csv").write_text("file,label,mask,source,camera\n" + "\n".join(lines) + "\n")
    return folder


@pytest.fixture
def corpus(tmp_path):
    parent = tmp_path / "real"
    truth_set(parent / "buildings" / "dresden", [("a.png", "authentic", "Nikon D70"), ("b.png", "authentic", "")])
    truth_set(parent / "pairs", [("a.png", "manipulated", ""), ("o.png", "authentic", "")])
    # A truth file inside a set belongs to that set, not to a set of its own.
    truth_set(parent / "pairs" / "nested", [("n.png", "authentic", "")])
    (parent / "README.md").parent.mkdir(parents=True, exist_ok=True)
    (parent / "README.md").write_text("not a set")
    return parent


def test_a_parent_folder_holds_one_set_per_truth_file(corpus):
    suite = read_suite([corpus])
    assert suite.name == "real" and len(suite.content_sha256) == 64
    sets = {c.name: c.conditions["set"] for c in suite.cases}
    assert sets == {"buildings_dresden__a": "buildings/dresden", "buildings_dresden__b": "buildings/dresden",
                    "pairs__a": "pairs", "pairs__o": "pairs"}
    case = next(c for c in suite.cases if c.name == "pairs__a")
    assert case.spliced and case.conditions["source"] == "repo@abc:pairs/a.png"


def test_several_suites_in_one_record_and_a_set_named_directly(corpus, tmp_path):
    other = truth_set(tmp_path / "extra", [("a.png", "authentic", "")])
    suite = read_suite([corpus / "pairs", other])
    assert suite.name == "pairs + extra"
    assert {c.name: c.conditions["set"] for c in suite.cases} == {"pairs__a": "pairs", "pairs__o": "pairs",
                                                                  "extra__a": "extra"}
    alone = read_suite([other])
    assert [(c.name, c.conditions["set"]) for c in alone.cases] == [("a", "extra")]
    # The hash covers every set: another set changes it.
    assert read_suite([corpus / "pairs"]).content_sha256 != suite.content_sha256


def test_two_sets_of_the_same_name_stay_apart(tmp_path):
    first = truth_set(tmp_path / "one" / "x", [("a.png", "authentic", "")])
    second = truth_set(tmp_path / "two" / "x", [("a.png", "authentic", "")])
    suite = read_suite([first, second])
    assert len({c.name for c in suite.cases}) == 2 and len({c.conditions["set"] for c in suite.cases}) == 2


def test_a_parent_without_any_set_is_refused(tmp_path):
    photo(tmp_path / "x" / "y.png")
    with pytest.raises(SuiteError, match="nor any set below it"):
        read_suite([tmp_path])
    with pytest.raises(SuiteError, match="not a folder"):
        read_suite([tmp_path / "missing"])


def _result(i, spliced, conditions):
    p = 0.5 if not spliced else 1e-4
    return CaseResult(f"c{i}", spliced, conditions, "0" * 64, VerdictLabel.CONSISTENT, p,
                      {"d": DetectorOutcome(Status.OK, p, 1 - p, None, 0.0)})


def test_conditions_naming_single_photos_stay_out_of_the_breakdown():
    results = [_result(i, i % 2 == 1, {"source": f"repo:{i}.jpg", "camera": f"cam {i % 16}",
                                       "set": "a" if i < 10 else "b", "kind": "k"})
               for i in range(24)]
    keys = {c.key for c in compute_methods(results, {"d": "1"}, 0.01)[0].by_condition}
    # 24 sources and 16 cameras for 24 photos name photos; 2 sets and 1 kind group them.
    assert keys == {"set", "kind"}
    few = [_result(i, i % 2 == 1, {"camera": f"cam {i}"}) for i in range(6)]
    assert {c.key for c in compute_methods(few, {"d": "1"}, 0.01)[0].by_condition} == {"camera"}
