"""Tables of plugin sections: CSV files beside the report, in the manifest, safe to open in a spreadsheet."""

import csv
import io
import json
from importlib.metadata import EntryPoint

import numpy as np
import pytest

from forensics_core import ENTRY_POINT_GROUP
from forensics_core.analysis import Options, analyze_evidence
from forensics_core.evidence import load_evidence
from forensics_core.manifest import MANIFEST_NAME
from forensics_core.output import write_findings
from forensics_core.plugins import PluginHost
from forensics_core.report import Table
from forensics_core.report.bundle import write_bundle
from forensics_core.report.plugin_sections import _tables
from forensics_core.report.render import ReportOptions
from report_helpers import hostile_jpeg
from table_fixture_plugins import FORMULAS, NUMBERS


def table_host(*names: str) -> PluginHost:
    host = PluginHost(allow=None, deny=())
    for name in names:
        host.load_entry_point(EntryPoint(name, f"table_fixture_plugins:{name}", ENTRY_POINT_GROUP))
    return host


def bundle_of(photo, folder, key, *plugins):
    host = table_host(*plugins)
    evidence = load_evidence(photo)
    findings = analyze_evidence(evidence, host, Options(case_id="2024/117", isolation="inline"))
    write_findings(findings, folder)
    write_bundle(findings, evidence, folder, key, host=host, options=ReportOptions(exhibit_id="EX-7"),
                 organisation="Forensic Lab")
    return folder


@pytest.fixture(scope="module")
def tabled_bundle(tmp_path_factory, key):
    folder = tmp_path_factory.mktemp("tabled")
    return bundle_of(hostile_jpeg(folder / "photo.jpg"), folder / "out", key, "tabled")


def rows_of(path):
    data = path.read_bytes()
    return list(csv.reader(io.StringIO(data.decode("utf-8"), newline="")))


def test_a_section_s_table_is_a_csv_beside_the_report_and_in_the_manifest(tabled_bundle):
    path = tabled_bundle / "tabled-lines.csv"
    rows = rows_of(path)
    assert rows[0] == ["line", "k1", "status", "flagged"]
    assert rows[1] == ["1", "-0.0149", "consistent", ""] and rows[2] == ["2", "0.5", "kept, with a comma", "True"]
    assert len(rows) == 1 + 2 + len(FORMULAS) + len(NUMBERS)
    assert rows_of(tabled_bundle / "tabled-windows.csv") == [["x", "y"]]
    listed = {f["name"]: f for f in json.loads((tabled_bundle / MANIFEST_NAME).read_text())["files"]}
    assert {"tabled-lines.csv", "tabled-windows.csv"} <= set(listed)
    assert listed["tabled-lines.csv"]["size"] == path.stat().st_size


def test_formula_like_cells_are_neutralised_and_numbers_are_kept(tabled_bundle):
    cells = {row[0]: row[2] for row in rows_of(tabled_bundle / "tabled-lines.csv")[3:]}
    texts = [cells[str(3 + i)] for i in range(len(FORMULAS) + len(NUMBERS))]
    assert texts[:len(FORMULAS)] == ["'" + f for f in FORMULAS]
    assert texts[len(FORMULAS):] == NUMBERS


def test_the_template_names_the_file_and_the_detector_section_lists_it(tabled_bundle):
    html = (tabled_bundle / "report.html").read_text()
    assert "Every line is in tabled-lines.csv (11 rows: every extracted line &lt;b&gt;)." in html
    assert "0 rows: in tabled-windows.csv, beside this report." in html
    assert "tables (CSV) tabled-lines.csv" in html
    assert "tabled-lines.csv (every extracted line &lt;b&gt;, 11 rows), tabled-windows.csv (0 rows)." in html


@pytest.mark.parametrize("plugin, reason", [
    ("table_ragged", "has rows whose length is not its 2 columns"),
    ("table_of_objects", "a table cell is a object, not a plain value"),
])
def test_a_malformed_table_fails_its_section_only(tmp_path, key, plugin, reason):
    folder = bundle_of(hostile_jpeg(tmp_path / "p.jpg"), tmp_path / "out", key, plugin, "tabled")
    html = (folder / "report.html").read_text()
    assert f"{plugin}: report section failed" in html and reason in html
    assert not list(folder.glob(f"{plugin}-*.csv")) and (folder / "tabled-lines.csv").is_file()


def test_numpy_cells_are_written_as_plain_numbers():
    from forensics_core.findings import DetectorFinding, Status

    finding = DetectorFinding(name="numpy tabled", version="1", plugin="p", status=Status.OK, summary="s",
                              score=None, p_value=None, nfa=None, details={}, parameters={}, elapsed_s=0.0)
    table = Table(["n", "x"], [[np.int64(3), np.float64(-0.25)], [np.bool_(True), np.float32(0.5)]], "numpy")
    rendered, files = _tables(finding, {"a/b": table})
    assert list(files) == ["numpy_tabled-a_b.csv"] and rendered[0].n_rows == 2
    data, mime = files["numpy_tabled-a_b.csv"]
    assert mime == "text/csv" and data.decode("utf-8").splitlines() == ["n,x", "3,-0.25", "True,0.5"]
