"""Detector sections: what each plugin contributes, rendered generically and contained.

Each detector's ``report_section`` is called on its own, in a forked
child as detectors are, and what it returns is rendered there: its figures
decoded and reduced for the page, its tables turned into CSV files, its
template filled in a sandboxed, autoescaping Jinja2 environment (a template
cannot reach Python internals, and every value from ``context`` is escaped
unless the plugin's own template text put the markup there). A detector whose ``report_section`` raises, returns something
other than a :class:`ReportSection`, or whose template fails, gets a section
that says so, followed by its finding in generic form; the report still renders.
"""

from __future__ import annotations

import io
import numbers
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np
from jinja2 import StrictUndefined
from jinja2.sandbox import ImmutableSandboxedEnvironment
from markupsafe import Markup
from PIL import Image

from ..containment import Child, PluginFault, can_fork, jobs_for, wait_any
from ..detector import Detector, implements
from ..evidence import Evidence
from ..findings import DetectorFinding, Status
from ..plugins import PluginHost, one_line
from . import images
from .sections import Figure, ReportSection, Table
from .tables import csv_bytes

_SAFE_NAME = re.compile(r"[^A-Za-z0-9_.-]+")
_CLASS_UNSAFE = re.compile(r"[^A-Za-z0-9_-]+")


@dataclass
class RenderedFigure:
    """A figure as a template sees it: ``{{ figures.key }}`` renders it inline.

    ``src`` (a ``data:`` URL) and ``caption`` are there for templates that lay
    out the image themselves. A placed figure (:meth:`fit`, :meth:`beside`)
    gets a class of its own and its sizes as stylesheet ``rules``: the
    report's Content-Security-Policy admits its one hashed stylesheet and no
    ``style`` attribute.
    """

    key: str
    data_url: str
    caption: str
    file_name: str
    used: bool = False
    aspect: float | None = None
    rules: list[str] = field(default_factory=list)

    @property
    def src(self) -> str:
        self.used = True
        return self.data_url

    def __html__(self) -> str:
        return self._figure("", "")

    def fit(self, height_mm: float) -> Markup:
        """The figure as ``{{ figures.key }}`` renders it, its image at most ``height_mm`` millimetres high.

        For a figure of the whole photo, which at the page's width would
        take a page of its own when the photo is portrait.
        """
        return self._figure("", f"max-height: {float(height_mm):g}mm; width: auto")

    def beside(self, height_mm: float) -> Markup:
        """The figure at the right of the text that follows it, ``height_mm`` millimetres high at most.

        At most half the page wide, so that the text beside it stays
        readable; tables after it start below it.
        """
        height = float(height_mm)
        # clear: a figure placed beside another would leave the text a sliver of the page between them.
        placed = "float: right; clear: right; margin: 0 0 2mm 4mm; "
        if self.aspect is None:
            return self._figure(placed + "width: 45%", f"max-height: {height:g}mm; width: auto")
        return self._figure(placed + f"width: {height * self.aspect:.1f}mm; max-width: 50%",
                            "width: 100%; height: auto")

    @property
    def css_class(self) -> str:
        return "fig-" + _CLASS_UNSAFE.sub("_", self.file_name)

    def _figure(self, figure_style: str, img_style: str) -> Markup:
        caption = Markup("<figcaption>{}</figcaption>").format(self.caption) if self.caption else ""
        placed = figure_style or img_style
        if figure_style:
            self.rules.append(f"figure.{self.css_class} {{ {figure_style} }}")
        if img_style:
            self.rules.append(f"figure.{self.css_class} img {{ {img_style} }}")
        classes = f"plugin-figure {self.css_class}" if placed else "plugin-figure"
        return Markup('<figure class="{}"><img src="{}" alt="{}">{}</figure>').format(
            classes, self.src, self.caption or self.key, caption)


@dataclass
class RenderedTable:
    """A table as a template sees it: the CSV file beside the report that holds it.

    ``{{ tables.key }}`` renders the one-line note that says where the rows are.
    """

    key: str
    file_name: str
    caption: str
    n_rows: int

    def __html__(self) -> str:
        rows = Markup("{} rows").format(self.n_rows)
        what = Markup("{} ({})").format(self.caption, rows) if self.caption else rows
        return Markup('<p class="note">{}: in {}, beside this report.</p>').format(what, self.file_name)


@dataclass
class DetectorSection:
    """One detector's section, ready for the report template.

    Attributes
    ----------
    finding : DetectorFinding
    title : str
    body : Markup or None
        The plugin's rendered template; None when the plugin gave none.
    failure : str or None
        Why the plugin's section could not be used, in one line.
    figures : list of RenderedFigure
        All figures; those the template did not place are shown after it.
    tables : list of RenderedTable
        The section's tables, each a CSV file beside the report.
    files : dict of str to (bytes, str)
        Files to write beside the report (full-resolution figures, the
        tables' CSV): name to (data, mime).
    """

    finding: DetectorFinding
    title: str
    body: Markup | None = None
    failure: str | None = None
    figures: list[RenderedFigure] = field(default_factory=list)
    tables: list[RenderedTable] = field(default_factory=list)
    files: dict[str, tuple[bytes, str]] = field(default_factory=dict)

    @property
    def css(self) -> str:
        """The stylesheet rules that size and place this section's figures (made by the core from numbers)."""
        return "\n".join(rule for f in self.figures for rule in f.rules)

    @property
    def unplaced_figures(self) -> list[RenderedFigure]:
        return [f for f in self.figures if not f.used]


class _Sandbox(ImmutableSandboxedEnvironment):
    """Autoescaping sandbox; undefined names fail loudly so a plugin author sees the mistake."""

    def __init__(self):
        super().__init__(autoescape=True, undefined=StrictUndefined)


_EXTENSIONS = {"image/png": "png", "image/jpeg": "jpg", "image/svg+xml": "svg"}


def _file_name(finding: DetectorFinding, key: object, extension: str) -> str:
    return f"{_SAFE_NAME.sub('_', finding.name)}-{_SAFE_NAME.sub('_', str(key))}.{extension}"


def _figures(finding: DetectorFinding, figs: dict[str, Figure]) -> tuple[list[RenderedFigure], dict[str, tuple[bytes, str]]]:
    rendered, files = [], {}
    for key, fig in figs.items():
        if not isinstance(fig, Figure):
            raise TypeError(f"figure {key!r} is a {type(fig).__name__}, not a Figure")
        data, mime = images.for_report(fig)
        name = _file_name(finding, key, _EXTENSIONS[fig.mime])
        files[name] = (fig.data, fig.mime)
        rendered.append(RenderedFigure(str(key), images.data_url(data, mime), str(fig.caption), name,
                                       aspect=_aspect(data, mime)))
    return rendered, files


_SVG_SIZE = re.compile(rb"<svg\b[^>]*?\swidth=\"([\d.]+)(?:pt|px)?\"[^>]*?\sheight=\"([\d.]+)(?:pt|px)?\"")


def _aspect(data: bytes, mime: str) -> float | None:
    """Width over height of an embedded figure, or None when its header does not say."""
    if mime == "image/svg+xml":
        m = _SVG_SIZE.search(data[:4096])
        width, height = (float(m.group(1)), float(m.group(2))) if m else (0.0, 0.0)
    else:
        with Image.open(io.BytesIO(data), formats=["PNG", "JPEG"]) as img:
            width, height = img.size
    return width / height if width > 0 and height > 0 else None


def _plain(value: object) -> Any:
    """A cell as a plain Python value: a numpy scalar would otherwise be written as its repr."""
    if value is None or isinstance(value, (str, bool)):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value)
    raise TypeError(f"a table cell is a {type(value).__name__}, not a plain value")


def _tables(finding: DetectorFinding,
            tables: dict[str, Table]) -> tuple[list[RenderedTable], dict[str, tuple[bytes, str]]]:
    rendered, files = [], {}
    for key, table in tables.items():
        if not isinstance(table, Table):
            raise TypeError(f"table {key!r} is a {type(table).__name__}, not a Table")
        columns = [str(c) for c in table.columns]
        rows = [[_plain(v) for v in row] for row in table.rows]
        if any(len(row) != len(columns) for row in rows):
            raise ValueError(f"table {key!r} has rows whose length is not its {len(columns)} columns")
        name = _file_name(finding, key, "csv")
        files[name] = (csv_bytes(columns, rows), "text/csv")
        rendered.append(RenderedTable(str(key), name, str(table.caption), len(rows)))
    return rendered, files


def _render(finding: DetectorFinding, section: object) -> DetectorSection:
    if not isinstance(section, ReportSection):
        raise TypeError(f"returned a {type(section).__name__}, not a ReportSection")
    figures, files = _figures(finding, dict(section.figures))
    tables, table_files = _tables(finding, dict(section.tables))
    template = _Sandbox().from_string(str(section.template))
    body = Markup(template.render(**dict(section.context), figures={f.key: f for f in figures},
                                  tables={t.key: t for t in tables}, finding=finding))
    return DetectorSection(finding, str(section.title), body=body, figures=figures, tables=tables,
                           files={**files, **table_files})


def _failed(finding: DetectorFinding, reason: str) -> DetectorSection:
    return DetectorSection(finding, f"{finding.name}: report section failed", failure=reason)


SECTION_TIMEOUT_S = 300.0


def _from_outcome(finding: DetectorFinding, error: BaseException | None, value: object) -> DetectorSection | None:
    """The section a ``report_section`` call's outcome gives, or None when it declined (returned None)."""
    if error is not None:
        return _failed(finding, f"its report_section raised {one_line(error)}")
    if value is None:
        return None
    try:
        return _render(finding, value)
    except Exception as exc:  # a plugin's template or figures may fail in any way; contain it
        return _failed(finding, f"its section could not be rendered: {one_line(exc)}")


def _rendered(detector: Detector, finding: DetectorFinding, evidence: Evidence) -> DetectorSection | None:
    """Call a detector's ``report_section`` and render what it returns; None when it declined.

    Runs where the method runs, in its contained child, so that decoding the
    plugin's figures and filling its template are contained too: a figure
    that crashes its decoder or hangs costs only that section.
    """
    try:
        value = detector.report_section(finding, evidence)
    except Exception as exc:
        return _from_outcome(finding, exc, None)
    return _from_outcome(finding, None, value)


def section_for(host: PluginHost | None, finding: DetectorFinding, evidence: Evidence,
                timeout_s: float | None = None) -> DetectorSection:
    """The section of one finding, from the plugin that registered its detector.

    Never raises: whatever the plugin does wrong (raising, hanging past
    ``timeout_s``, at most :data:`SECTION_TIMEOUT_S`, ending its process)
    becomes the section's ``failure``; the method runs in a child process, as
    detectors do.
    """
    return sections_for(host, [finding], evidence, timeout_s, jobs=1)[0]


def sections_for(host: PluginHost | None, findings: Sequence[DetectorFinding], evidence: Evidence,
                 timeout_s: float | None = None, jobs: int = 1) -> list[DetectorSection]:
    """The sections of ``findings``, in their order, with ``jobs`` ``report_section`` calls running at once.

    Each call runs contained as in :func:`section_for`, which this is with
    ``jobs=1``, on large photos or where the platform cannot fork
    (:func:`~forensics_core.containment.jobs_for`; without fork the calls
    run in this process); the sections are the same whatever ``jobs`` is.
    """
    jobs = jobs_for(evidence.info.width * evidence.info.height, jobs)
    out: dict[int, DetectorSection] = {}
    pending: list[tuple[int, Callable[[], DetectorSection | None]]] = []
    for i, finding in enumerate(findings):
        entry = host.registered(finding) if host is not None else None
        # A detector that was not applied measured nothing: its entry is its status and reason, and its plugin is
        # not imported for it.
        if entry is None or finding.status is Status.SKIPPED or not implements(entry.detector, "report_section"):
            out[i] = DetectorSection(finding, finding.name)
        elif can_fork():
            pending.append((i, partial(_rendered, entry.detector, finding, evidence)))
        else:
            out[i] = _rendered(entry.detector, finding, evidence) or DetectorSection(finding, finding.name)
    running: dict[Child, int] = {}
    while pending or running:
        while pending and len(running) < jobs:
            i, call = pending.pop(0)
            running[Child(call, SECTION_TIMEOUT_S if timeout_s is None else min(timeout_s, SECTION_TIMEOUT_S))] = i
        for child in wait_any(list(running)):
            i = running.pop(child)
            outcome, _ = child.collect()
            section = (_from_outcome(findings[i], PluginFault(outcome[1]), None) if outcome[0] == "error"
                       else outcome[1])
            out[i] = section or DetectorSection(findings[i], findings[i].name)
    return [out[i] for i in range(len(findings))]
