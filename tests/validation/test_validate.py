"""A whole validation run with real worker processes, its record and page, and the report that reads it."""

import json

import pytest
from plugin_hosts import fixture_host

from forensics_core.analysis import Options
from forensics_core.validation import read_record, synthetic_suite, validate
from forensics_core.validation.record import VERDICT


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("validation")
    host = fixture_host("squares", "observer", module="validation_fixture")
    suite = synthetic_suite(host, out / "cases", seed=3, count=12)
    done = []
    record = validate(suite, out, host, Options(), workers=2, on_done=done.append, seed=3, count=12)
    return out, record, done


def test_every_photo_is_analysed_in_the_workers(run):
    out, record, done = run
    assert len(done) == 24 and all(r.error is None for r in done)
    assert len(list((out / "findings").glob("*.json"))) == 24
    assert record.dataset.n_spliced == 12 and record.dataset.n_authentic == 12 and record.dataset.seed == 3


def test_detector_and_verdict_figures(run):
    _, record, _ = run
    square = record.method("square")
    assert square.version == "2.0"
    assert square.auc == 1.0 and square.auc_ci == (1.0, 1.0)
    assert square.tpr_at_fpr == {"0.01": 1.0, "0.05": 1.0}
    op = square.operating_point
    assert op.rule == "p-value below 0.01"
    # The faint squares (every fourth) stay below the decision level.
    assert (op.tpr.k, op.tpr.n, op.fpr.k) == (9, 12, 0)
    assert square.localisation.n == 12 and square.localisation.found.k == 9
    assert 0.0 < square.localisation.f1_mean <= 1.0
    # Per condition too (the per-set figures of a corpus), over that condition's manipulated photos.
    by_kind = {c.value: c.localisation for c in square.by_condition if c.key == "kind"}
    assert by_kind["bright"].n + by_kind["faint"].n == 12 and by_kind["bright"].f1_mean > by_kind["faint"].f1_mean
    observer = record.method("observer")
    assert observer.declined_spliced.value == 1.0 and observer.auc == 0.5
    verdict = record.method(VERDICT)
    assert verdict.operating_point.tpr.k == 9 and verdict.operating_point.fpr.k == 0
    # The verdict's localisation is the report's Where map: the maps of the detectors that found something.
    assert verdict.localisation.n == 12
    wheres = [c["where"] for c in record.cases if c["spliced"]]
    assert len(wheres) == 12 and all(set(w) == {"mcc", "iou", "f1"} for w in wheres)
    # A faint square the detector does not call is outlined nowhere on page 1, so the Where map misses it.
    assert verdict.localisation.found.k <= square.localisation.found.k


def test_per_condition_breakdown(run):
    _, record, _ = run
    rows = {(c.key, c.value): c for c in record.method("square").by_condition}
    assert rows[("kind", "faint")].tpr.value == 0 and rows[("kind", "faint")].authentic_pool == "all"
    assert rows[("kind", "bright")].tpr.value == 1
    assert rows[("size", "small")].authentic_pool == "same"
    assert rows[("generator", "square")].n_spliced == 12


def test_record_round_trips_and_is_reproducible(run, tmp_path):
    out, record, _ = run
    again = read_record(out / "validation.json")
    assert again == record
    host = fixture_host("squares", "observer", module="validation_fixture")
    suite = synthetic_suite(host, tmp_path / "cases", seed=3, count=12)
    assert suite.content_sha256 == record.dataset.content_sha256
    second = validate(suite, tmp_path, host, Options(), workers=1, seed=3, count=12)
    assert [m.auc for m in second.methods] == [m.auc for m in record.methods]
    assert second.cases == [{**c} for c in record.cases]


def test_record_measures_cross_validated_likelihood_ratios(run):
    out, record, _ = run
    lr = record.likelihood_ratios
    assert lr["all"]["square"]["n_hp"] == 12 and lr["all"]["square"]["n_hd"] == 12
    # The squares detector separates most photos: its LRs cost far less than LR 1's 1 bit; the observer never
    # states a p-value, so its LR is 1 throughout.
    assert lr["all"]["square"]["cllr"] < 0.6 and lr["all"]["observer"]["cllr"] == pytest.approx(1.0)
    assert lr["all"][VERDICT]["cllr_min"] <= lr["all"][VERDICT]["cllr"]
    assert len(lr["llrs"][VERDICT]["hp"]) == 12
    html = (out / "validation.html").read_text()
    assert "Cllr_min" in html and "Tippett plots" in html


def test_page_has_roc_curves_and_tables(run):
    out, _, _ = run
    html = (out / "validation.html").read_text()
    assert "data:image/svg+xml;base64," in html and "TPR at FPR 5%" in html and "<script" not in html
    assert "kind = faint" in html


def test_a_plugin_that_yields_garbage_is_reported_and_left_out(tmp_path):
    host = fixture_host("squares", "broken_generator", module="validation_fixture")
    problems = []
    suite = synthetic_suite(host, tmp_path, seed=1, count=2, on_problem=problems.append)
    assert len(suite.cases) == 4
    assert problems[0].detector == "broken_generator" and "not SyntheticCase" in problems[0].reason


def test_unreadable_records_are_refused_in_one_line(tmp_path):
    bad = tmp_path / "v.json"
    bad.write_text("{nope")
    with pytest.raises(ValueError, match="not JSON"):
        read_record(bad)
    bad.write_text(json.dumps({"format": "other"}))
    with pytest.raises(ValueError, match="not a validation record"):
        read_record(bad)
