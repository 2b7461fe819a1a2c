"""What a detector contributes to the report through its ``report_section``."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class Figure:
    """An image the section's template refers to by its key in ``ReportSection.figures``.

    Parameters
    ----------
    data : bytes
        Encoded image.
    mime : str
        ``image/png`` or ``image/svg+xml``.
    caption : str
        Plain text; escaped when rendered.
    """

    data: bytes
    mime: str
    caption: str = ""


@dataclass(frozen=True)
class Table:
    """A table too long for the page, written beside the report as ``<detector>-<key>.csv``.

    The section's template refers to it by its key in ``ReportSection.tables``
    (``{{ tables.lines.file_name }}``, ``.caption``, ``.n_rows``), to say in
    one line which file holds what the page leaves out.

    Parameters
    ----------
    columns : list of str
        The header row.
    rows : list of list
        Plain values (str, int, float, bool or None, which is written as an
        empty cell), one per column.
    caption : str
        What the table holds, in a phrase; plain text, escaped when rendered.
    """

    columns: list[str]
    rows: list[list[Any]]
    caption: str = ""


@dataclass(frozen=True)
class ReportSection:
    """One detector's section of the report.

    Parameters
    ----------
    title : str
        Section heading.
    template : str
        Jinja2 source rendered with autoescape on, with ``context``,
        ``figures`` (each rendered by the report as an inline image) and
        ``tables`` (each a CSV file beside the report: its ``file_name``,
        ``caption`` and ``n_rows``).
    context : dict
        Values the template uses.
    figures : dict of str to Figure
    tables : dict of str to Table
        Long tables (every line, every candidate...) kept out of the page.
    """

    title: str
    template: str
    context: dict[str, Any] = field(default_factory=dict)
    figures: dict[str, Figure] = field(default_factory=dict)
    tables: dict[str, Table] = field(default_factory=dict)
