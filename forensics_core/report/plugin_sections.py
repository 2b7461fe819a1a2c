"""Detector sections: what each plugin contributes, rendered generically and contained.

Each plugin's ``forensics_report_section`` is called on its own, in a forked
child as detectors are, and what it returns is rendered there: its figures
decoded and reduced for the page, its template filled in a sandboxed,
autoescaping Jinja2 environment (a template cannot reach Python internals,
and every value from ``context`` is escaped unless the plugin's own template
text put the markup there). A plugin whose hook raises, returns something
other than a :class:`ReportSection`, or whose template fails, gets a section
that says so, followed by its finding in generic form; the report still renders.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial

from jinja2 import StrictUndefined
from jinja2.sandbox import ImmutableSandboxedEnvironment
from markupsafe import Markup

from ..containment import Child, PluginFault, can_fork, jobs_for, wait_any
from ..evidence import Evidence
from ..findings import DetectorFinding
from ..plugins import PluginHost, one_line
from . import images
from .sections import Figure, ReportSection

_SAFE_NAME = re.compile(r"[^A-Za-z0-9_.-]+")


@dataclass
class RenderedFigure:
    """A figure as a template sees it: ``{{ figures.key }}`` renders it inline.

    ``src`` (a ``data:`` URL) and ``caption`` are there for templates that lay
    out the image themselves.
    """

    key: str
    data_url: str
    caption: str
    file_name: str
    used: bool = False

    @property
    def src(self) -> str:
        self.used = True
        return self.data_url

    def __html__(self) -> str:
        caption = Markup("<figcaption>{}</figcaption>").format(self.caption) if self.caption else ""
        return Markup('<figure class="plugin-figure"><img src="{}" alt="{}">{}</figure>').format(
            self.src, self.caption or self.key, caption)


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
    files : dict of str to (bytes, str)
        Full-resolution figure files to write beside the report: name to (data, mime).
    """

    finding: DetectorFinding
    title: str
    body: Markup | None = None
    failure: str | None = None
    figures: list[RenderedFigure] = field(default_factory=list)
    files: dict[str, tuple[bytes, str]] = field(default_factory=dict)

    @property
    def unplaced_figures(self) -> list[RenderedFigure]:
        return [f for f in self.figures if not f.used]


class _Sandbox(ImmutableSandboxedEnvironment):
    """Autoescaping sandbox; undefined names fail loudly so a plugin author sees the mistake."""

    def __init__(self):
        super().__init__(autoescape=True, undefined=StrictUndefined)


_EXTENSIONS = {"image/png": "png", "image/jpeg": "jpg", "image/svg+xml": "svg"}


def _figures(finding: DetectorFinding, figs: dict[str, Figure]) -> tuple[list[RenderedFigure], dict[str, tuple[bytes, str]]]:
    rendered, files = [], {}
    for key, fig in figs.items():
        if not isinstance(fig, Figure):
            raise TypeError(f"figure {key!r} is a {type(fig).__name__}, not a Figure")
        data, mime = images.for_report(fig)
        name = f"{_SAFE_NAME.sub('_', finding.name)}-{_SAFE_NAME.sub('_', str(key))}.{_EXTENSIONS[fig.mime]}"
        files[name] = (fig.data, fig.mime)
        rendered.append(RenderedFigure(str(key), images.data_url(data, mime), str(fig.caption), name))
    return rendered, files


def _render(finding: DetectorFinding, section: object) -> DetectorSection:
    if not isinstance(section, ReportSection):
        raise TypeError(f"returned a {type(section).__name__}, not a ReportSection")
    figures, files = _figures(finding, dict(section.figures))
    template = _Sandbox().from_string(str(section.template))
    body = Markup(template.render(**dict(section.context), figures={f.key: f for f in figures}, finding=finding))
    return DetectorSection(finding, str(section.title), body=body, figures=figures, files=files)


def _failed(finding: DetectorFinding, reason: str) -> DetectorSection:
    return DetectorSection(finding, f"{finding.name}: report section failed", failure=reason)


SECTION_TIMEOUT_S = 300.0


def _from_outcome(finding: DetectorFinding, error: BaseException | None, value: object) -> DetectorSection | None:
    """The section a hook's outcome gives, or None when the hook declined (returned None)."""
    if error is not None:
        return _failed(finding, f"its report hook raised {one_line(error)}")
    if value is None:
        return None
    try:
        return _render(finding, value)
    except Exception as exc:  # a plugin's template or figures may fail in any way; contain it
        return _failed(finding, f"its section could not be rendered: {one_line(exc)}")


def _rendered(impl: Callable[..., object], finding: DetectorFinding, evidence: Evidence) -> DetectorSection | None:
    """Call a plugin's section hook and render what it returns; None when it declined.

    Runs where the hook runs, in its contained child, so that decoding the
    plugin's figures and filling its template are contained too: a figure
    that crashes its decoder or hangs costs only that section.
    """
    try:
        value = impl(finding=finding, evidence=evidence)
    except Exception as exc:
        return _from_outcome(finding, exc, None)
    return _from_outcome(finding, None, value)


def section_for(host: PluginHost | None, finding: DetectorFinding, evidence: Evidence,
                timeout_s: float | None = None) -> DetectorSection:
    """The section of one finding, from the plugin that registered its detector.

    Never raises: whatever the plugin does wrong (raising, hanging past
    ``timeout_s``, at most :data:`SECTION_TIMEOUT_S`, ending its process)
    becomes the section's ``failure``; the hook runs in a child process, as
    detectors do.
    """
    return sections_for(host, [finding], evidence, timeout_s, jobs=1)[0]


def sections_for(host: PluginHost | None, findings: Sequence[DetectorFinding], evidence: Evidence,
                 timeout_s: float | None = None, jobs: int = 1) -> list[DetectorSection]:
    """The sections of ``findings``, in their order, with ``jobs`` section hooks running at once.

    Each hook runs contained as in :func:`section_for`, which this is with
    ``jobs=1``, on large photos or where the platform cannot fork
    (:func:`~forensics_core.containment.jobs_for`; without fork the hooks
    run in this process); the sections are the same whatever ``jobs`` is.
    """
    jobs = jobs_for(evidence.info.width * evidence.info.height, jobs)
    out: dict[int, DetectorSection] = {}
    pending: list[tuple[int, Callable[[], DetectorSection | None]]] = []
    for i, finding in enumerate(findings):
        impl = (host.implementation("forensics_report_section", finding.plugin)
                if host is not None and finding.plugin in host.records else None)
        if impl is None:
            out[i] = DetectorSection(finding, finding.name)
        elif can_fork():
            pending.append((i, partial(_rendered, impl, finding, evidence)))
        else:
            out[i] = _rendered(impl, finding, evidence) or DetectorSection(finding, finding.name)
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
