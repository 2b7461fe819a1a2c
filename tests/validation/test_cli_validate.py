"""`forensics validate` on the command line, and a report that states the figures it wrote."""

import json
import subprocess
import sys

import pytest


def forensics(*args, **kw):
    return subprocess.run([sys.executable, "-m", "forensics_core", *map(str, args)], capture_output=True, text=True,
                          timeout=600, **kw)


@pytest.fixture(scope="module")
def validated(tmp_path_factory):
    out = tmp_path_factory.mktemp("validate")
    run = forensics("validate", "synthetic", "--out", out, "--count", 1, "--detectors", "metadata", "--workers", 2)
    assert run.returncode == 0, run.stderr
    return out, run


def test_validate_writes_record_page_and_a_table(validated):
    out, run = validated
    record = json.loads((out / "validation.json").read_text())
    assert record["dataset"]["name"] == "synthetic" and record["dataset"]["count"] == 1
    assert {m["name"] for m in record["methods"]} == {"metadata", "verdict"}
    assert record["dataset"]["n_spliced"] >= 2 and len(record["cases"]) == record["dataset"]["n_cases"]
    assert (out / "validation.html").is_file()
    assert "fused verdict" in run.stdout and "AUC" in run.stdout


def test_a_report_made_afterwards_states_those_figures(validated, tmp_path, data_dir):
    out, _ = validated
    run = forensics("analyze", data_dir / "exif" / "Canon_40D.jpg", "--out", tmp_path, "--detectors", "metadata",
                    "--format", "html", "--validation", out / "validation.json")
    assert run.returncode == 0, run.stderr
    html = (tmp_path / "Canon_40D" / "report.html").read_text()
    sha = json.loads((out / "validation.json").read_text())["dataset"]["content_sha256"]
    assert "from the validation record" in html and sha in html
    assert "fused verdict" in html


def test_bad_suites_and_records_get_one_line(tmp_path, data_dir):
    run = forensics("validate", tmp_path / "nowhere", "--out", tmp_path / "o")
    assert run.returncode == 1 and run.stderr.count("\n") == 1 and "not a folder" in run.stderr
    bad = tmp_path / "v.json"
    bad.write_text("{}")
    run = forensics("analyze", data_dir / "exif" / "Canon_40D.jpg", "--out", tmp_path, "--detectors", "metadata",
                    "--validation", bad)
    assert run.returncode == 2 and "Traceback" not in run.stderr and "not a validation record" in run.stderr


def test_several_sets_are_measured_in_one_record(tmp_path):
    import numpy as np
    from PIL import Image

    for where in ("one", "two"):
        folder = tmp_path / "corpus" / where
        folder.mkdir(parents=True)
        for i in range(2):
            Image.fromarray(np.full((24, 32), 40 + 60 * i, np.uint8)).save(folder / f"p{i}.png")
        (folder / "truth.csv").write_text("file,label,mask,source,camera\np0.png,authentic,,a,\np1.png,manipulated,,b,\n")
    run = forensics("validate", tmp_path / "corpus" / "one", tmp_path / "corpus" / "two", "--out", tmp_path / "o",
                    "--detectors", "metadata", "--workers", 1)
    assert run.returncode == 0, run.stderr
    record = json.loads((tmp_path / "o" / "validation.json").read_text())
    assert record["dataset"]["name"] == "one + two" and record["dataset"]["n_cases"] == 4
    assert sorted((c["name"], c["conditions"]["set"]) for c in record["cases"]) == [
        ("one__p0", "one"), ("one__p1", "one"), ("two__p0", "two"), ("two__p1", "two")]
    assert {c["name"] for c in record["null_checks"]} == {"metadata", "verdict"}
