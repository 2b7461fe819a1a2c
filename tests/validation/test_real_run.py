"""A run over a parent folder of sets: null checks, the convicted authentic photos with thumbnails, the report's
section stating real and synthetic records, and `make validate-real` without the corpus."""

import hashlib
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from plugin_hosts import fixture_host

from forensics_core.analysis import Options
from forensics_core.findings import Findings
from forensics_core.report import error_rates as rates_module
from forensics_core.report.error_rates import given_error_rates, shipped_error_rates
from forensics_core.report.render import _environment
from forensics_core.validation import read_record, read_suite, validate
from forensics_core.validation.record import SHIPPED, SHIPPED_INNOCENT, SHIPPED_REAL, VERDICT

REPO = Path(__file__).resolve().parents[2]


def noise(seed, square=False):
    pixels = np.random.default_rng(seed).uniform(0, 110, (64, 64)).astype(np.uint8)
    if square:
        pixels[20:36, 24:40] = 250
    return pixels


def make_set(folder, photos):
    """``photos``: (file, label, pixels); written as PNG with a truth.csv naming each one's source."""
    folder.mkdir(parents=True)
    for name, _, pixels in photos:
        Image.fromarray(pixels).save(folder / name)
    rows = "".join(f"{n},{label},,test:{folder.name}/{n},\n" for n, label, _ in photos)
    (folder / "truth.csv").write_text("file,label,mask,source,camera\n" + rows)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    parent = tmp_path_factory.mktemp("real")
    # An "authentic" photo with a bright square: the fixture detector convicts it, as a real false alarm.
    make_set(parent / "cameras" / "one", [(f"a{i}.png", "authentic", noise(i, square=i == 0)) for i in range(5)])
    make_set(parent / "pairs", [(f"o{i}.png", "authentic", noise(10 + i)) for i in range(3)]
             + [(f"f{i}.png", "manipulated", noise(20 + i, square=True)) for i in range(3)])
    out = tmp_path_factory.mktemp("out")
    watched = parent / "cameras" / "one" / "a0.png"
    before = hashlib.sha256(watched.read_bytes()).hexdigest()
    host = fixture_host("squares", "observer", module="validation_fixture")
    record = validate(read_suite([parent]), out, host, Options(), workers=1)
    assert hashlib.sha256(watched.read_bytes()).hexdigest() == before
    return out, record


def test_record_holds_null_checks_and_per_set_figures(run):
    out, record = run
    assert read_record(out / "validation.json") == record
    checks = {c.name: c for c in record.null_checks}
    assert set(checks) == {"square", "observer", VERDICT}
    square = checks["square"]
    assert square.convicted_cases == ["cameras_one__a0"] and square.convicted.n == 8
    assert square.n_tested == 8 and square.below["0.01"].k == 1
    assert checks["observer"].n_tested == 0
    by_set = {s.set: s for s in square.by_set}
    assert by_set["cameras/one"].auc is None and by_set["cameras/one"].fpr.k == 1
    assert by_set["pairs"].auc == 1.0 and by_set["pairs"].fpr.k == 0
    saved = json.loads((out / "validation.json").read_text())
    assert saved["null_checks"][0]["below"]["0.001"]["n"] >= 0
    # Sources name single photos: per photo only, never in the breakdown.
    assert saved["cases"][0]["conditions"]["source"].startswith("test:")
    assert {c.key for m in record.methods for c in m.by_condition} == {"set"}


def test_page_shows_the_curves_and_the_convicted_photo_with_its_map(run):
    out, _ = run
    thumb = out / "thumbnails" / "cameras_one__a0.square.jpg"
    with Image.open(thumb) as img:
        pixels = np.asarray(img.convert("RGB"), dtype=int)
    # The flagged square is tinted red; the rest is grey noise.
    assert (pixels[..., 0] - pixels[..., 1] > 80).any() and max(img.size) <= 192
    html = (out / "validation.html").read_text()
    assert "Does each test hold on authentic photos?" in html and "empirical CDF of the p-values of square" in html
    assert "Authentic photos called inconsistent" in html and "cameras_one__a0" in html
    assert "data:image/jpeg;base64," in html and "<script" not in html
    assert "cameras/one" in html and "By set" in html


def test_report_states_real_figures_first_then_synthetic(run, monkeypatch):
    out, record = run
    findings = Findings.from_dict(json.loads(next((out / "findings").glob("*.json")).read_text()))
    shipped = {SHIPPED_REAL: record, SHIPPED_INNOCENT: None, SHIPPED: None}
    monkeypatch.setattr(rates_module, "shipped_record", lambda name: shipped[name])
    section = shipped_error_rates(findings)
    assert [r.heading for r in section.records] == ["Real photos"]
    assert section.records[0].data.startswith("8 authentic and 3 manipulated photos")
    assert "cameras/one (5 authentic)" in section.records[0].data and "pairs (3 authentic, 3 manipulated)" in section.records[0].data
    assert "not generated" in section.records[0].data
    assert "No validation record on generated photos" in section.missing[-1]

    shipped[SHIPPED] = record
    assert [r.heading for r in shipped_error_rates(findings).records] == ["Real photos", "Synthetic photos"]

    shipped[SHIPPED_REAL] = None
    html = _environment().get_template("_error_rates.html.j2").render(error_rates=shipped_error_rates(findings))
    assert "No validation record on real camera photos is shipped" in html and "4.1 Synthetic photos" in html

    given = given_error_rates(findings, record, "the validation record x.json")
    assert len(given.records) == 1 and not given.missing


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_make_validate_real_without_the_corpus_says_so_and_succeeds(tmp_path):
    run = subprocess.run(["make", "-s", "-C", str(REPO), "validate-real", f"REAL={tmp_path / 'absent'}",
                          f"OUT={tmp_path / 'out'}"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "real corpus is absent" in run.stdout and not (tmp_path / "out").exists()
