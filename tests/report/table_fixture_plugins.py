"""Plugins whose report sections carry tables, well formed or not, loaded through real entry points."""

from forensics_core import Detector, DetectorResult, DetectorSpec, Status, hookimpl
from forensics_core.report import ReportSection, Table

FORMULAS = ["=HYPERLINK(\"http://x\")", "+SUM(A1:A2)", "-2+3", "@cmd", "\tlead", "\rlead"]
"""Cells a spreadsheet would run as formulas; each must come out with a leading apostrophe."""

NUMBERS = ["-0.0149", "+3", "-1e-05"]
"""Text that is a number, which starts like a formula but must stay as it is."""


class _Detector(Detector):
    """A fixture plugin that is also the one detector it registers."""

    name = "base"

    @property
    def spec(self):
        return DetectorSpec(self.name, "1.0", f"Table fixture {self.name}.")

    @hookimpl
    def forensics_register_detectors(self, register):
        register(self)

    def analyze(self, evidence, params):
        return DetectorResult(Status.OK, f"{self.name} measured 3 lines.", score=0.1)


class Tabled(_Detector):
    """A section whose per-line table goes beside the report, with hostile and numeric cells."""

    name = "tabled"

    def report_section(self, finding, evidence):
        rows = [[1, -0.0149, "consistent", None], [2, 0.5, "kept, with a comma", True]]
        rows += [[3 + i, 0.0, text, False] for i, text in enumerate(FORMULAS + NUMBERS)]
        return ReportSection(
            title="Tabled fixture detector",
            template=("<p class='tabled-intro'>Every line is in {{ tables.lines.file_name }} "
                      "({{ tables.lines.n_rows }} rows: {{ tables.lines.caption }}).</p>{{ tables.windows }}"),
            tables={"lines": Table(["line", "k1", "status", "flagged"], rows, "every extracted line <b>"),
                    "windows": Table(["x", "y"], [], "")},
        )


class TableRagged(_Detector):
    """A table whose row is shorter than its header: the section fails, the report does not."""

    name = "table_ragged"

    def report_section(self, finding, evidence):
        return ReportSection("Ragged", "<p>ragged</p>", tables={"lines": Table(["a", "b"], [[1]], "short row")})


class TableOfObjects(_Detector):
    """A table whose cell is not a plain value."""

    name = "table_of_objects"

    def report_section(self, finding, evidence):
        return ReportSection("Objects", "<p>objects</p>", tables={"lines": Table(["a"], [[object()]], "")})


tabled, table_ragged, table_of_objects = Tabled(), TableRagged(), TableOfObjects()
