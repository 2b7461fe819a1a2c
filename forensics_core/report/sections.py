"""What a plugin contributes to the report through ``forensics_report_section``."""

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
class ReportSection:
    """One detector's section of the report.

    Parameters
    ----------
    title : str
        Section heading.
    template : str
        Jinja2 source rendered with autoescape on, with ``context`` and
        ``figures`` (each rendered by the report as an inline image).
    context : dict
        Values the template uses.
    figures : dict of str to Figure
    """

    title: str
    template: str
    context: dict[str, Any] = field(default_factory=dict)
    figures: dict[str, Figure] = field(default_factory=dict)
