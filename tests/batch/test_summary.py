"""summary.csv and summary.json."""

import csv
import io
import json

from forensics_core.batch.summary import Row, counts, detector_names, to_csv, write_summary


def test_csv_has_a_column_pair_per_detector_and_defuses_formulas():
    rows = [
        Row("=HYPERLINK(\"http://x\").jpg", "ab" * 32, "analysed", "consistent", 1.48, "out/x", time_s=1.5,
            attempts=1, detectors={"steady": {"status": "ok", "score": 0.25}}),
        Row("b.jpg", None, "failed", error="-not an image"),
    ]
    names = detector_names(rows, ["steady", "cfa"])
    assert names == ["steady", "cfa"]
    table = list(csv.DictReader(io.StringIO(to_csv(rows, names).decode())))
    assert table[0]["photo"].startswith("'=") and table[1]["error"] == "'-not an image"
    assert table[0]["steady.status"] == "ok" and float(table[0]["steady.score"]) == 0.25
    assert table[0]["cfa.status"] == "" and table[1]["time_s"] == ""
    assert float(table[0]["log10_lr"]) == 1.48 and table[1]["log10_lr"] == ""


def test_csv_shows_control_and_bidirectional_characters_escaped():
    rows = [Row("photo\x1b[31m\u202egpj.exe", None, "failed", error="bad\x07")]
    text = to_csv(rows, []).decode()
    assert "\x1b" not in text and "\u202e" not in text and "\x07" not in text
    assert "photo\\x1b[31m\\u202egpj.exe" in text and "bad\\x07" in text


def test_summary_json_counts_outcomes_and_verdicts(tmp_path):
    rows = [Row("a", "1", "analysed", "consistent"), Row("b", "1", "duplicate", "consistent"),
            Row("c", None, "failed", error="empty file"), Row("d", "2", "pending")]
    json_path, csv_path = write_summary(tmp_path, rows, [], {"workers": "test"})
    doc = json.loads(json_path.read_text())
    assert doc["counts"] == counts(rows)
    assert doc["counts"]["analysed"] == 1 and doc["counts"]["pending"] == 1
    assert doc["counts"]["verdicts"] == {"consistent": 2}
    assert [r["photo"] for r in doc["photos"]] == ["a", "b", "c", "d"]
    assert csv_path.read_text().count("\n") == 5
