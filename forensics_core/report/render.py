"""Render the evidence report: HTML from the Jinja2 templates, PDF from that HTML.

Both outputs come from the same templates: ``report.html`` for the screen
(self-contained, no JavaScript, a strict Content-Security-Policy) and
``report.pdf`` by WeasyPrint with the print rules of the same stylesheet.
Every value taken from the evidence reaches the templates as plain data and
is escaped by autoescape; nothing from the evidence is marked safe.
"""

from __future__ import annotations

import base64
import hashlib
import json
import shlex
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import datetime, timezone
from importlib.resources import files
from pathlib import Path
from typing import TYPE_CHECKING, Any

from jinja2 import Environment, FunctionLoader, StrictUndefined
from markupsafe import Markup

from ..calibration.model import WEAK_SUPPORT_LR, supports, verbal
from ..contracts import Processing, SourceAttribution
from ..defaults import PAPER_SIZES
from ..evidence import Evidence
from ..findings import ExifSummary, Findings, Status, Verdict
from ..fusion import LR_POLICY
from ..plugins import PluginHost, localise_map
from ..text import visible
from ..validation.null_check import VERDICT
from ..validation.record import SHIPPED_REALISTIC, ValidationRecord, shipped_record
from . import images, wording
from .error_rates import ErrorRates, given_error_rates, shipped_error_rates
from .tables import csv_bytes
from .plugin_sections import DetectorSection, sections_for

if TYPE_CHECKING:
    from .layout_process import LayoutProcess

TEMPLATES_PACKAGE = "forensics_core.templates"
METADATA_CSV = "metadata.csv"
"""Every metadata tag, written beside the report: pages of tags help no reader of the PDF."""
NOT_GIVEN = "not given"
_DETAILS_LIMIT = 3000

# The libraries that make the report itself (the analysis libraries are in the findings).
_REPORT_PACKAGES = ("jinja2", "weasyprint", "pydyf", "pyhanko", "cryptography")

_ORIENTATIONS = {
    1: "1 (normal)", 2: "2 (mirrored horizontally)", 3: "3 (rotated 180°)", 4: "4 (mirrored vertically)",
    5: "5 (mirrored, rotated 90° counter-clockwise)", 6: "6 (rotated 90° clockwise for display)",
    7: "7 (mirrored, rotated 90° clockwise)", 8: "8 (rotated 90° counter-clockwise for display)",
}


@dataclass(frozen=True)
class SignatureInfo:
    """What the signature block says about who signs and with which certificate."""

    examiner: str
    organisation: str
    subject: str
    fingerprint: str
    self_signed: bool
    valid_from: str
    valid_to: str


@dataclass(frozen=True)
class ReportOptions:
    """Choices for one report.

    Parameters
    ----------
    exhibit_id : str or None
        The exhibit number the evidence carries in the case.
    paper : {"a4", "letter"}
    report_date : str or None
        ISO date-time (UTC) printed as the report's date; default now.
    validation : ValidationRecord or None
        The one error-rate record to state; default the records shipped
        with the release, on real photos (``make validate-real``) and on
        synthetic ones (``make validate``), those that exist.
    validation_source : str or None
        Where ``validation`` was read from, as printed in the report.
    jobs : int
        Plugins' section hooks run at once, each in its own process; the
        report is the same whatever it is.
    """

    exhibit_id: str | None = None
    paper: str = "a4"
    report_date: str | None = None
    validation: ValidationRecord | None = None
    validation_source: str | None = None
    jobs: int = 1


@dataclass
class RenderedReport:
    """The report's HTML, its detector sections (with the figure files to write), the core's own files to write
    beside it (name to bytes: the tables too long for the page), and what the PDF renderer refused."""

    html: str
    sections: list[DetectorSection]
    files: dict[str, bytes] = field(default_factory=dict)
    refused_urls: list[str] = field(default_factory=list)


def template_text(name: str) -> str:
    """The text of one template or asset shipped in ``forensics_core.templates``."""
    return files(TEMPLATES_PACKAGE).joinpath(name).read_text(encoding="utf-8")


def _report_packages() -> dict[str, str | None]:
    from importlib.metadata import PackageNotFoundError, version

    found: dict[str, str | None] = {}
    for name in _REPORT_PACKAGES:
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            found[name] = None
    return found


def _num(value: float | None) -> str:
    """A number to three significant figures, or a dash when the detector gives none."""
    return "—" if value is None else f"{value:.3g}"


def _utc_text(value: str) -> str:
    """``2024-05-01T10:00:00Z`` as ``2024-05-01 10:00:00 UTC``; other text unchanged."""
    return value[:-1].replace("T", " ") + " UTC" if value.endswith("Z") and "T" in value else value


def _pretty(value: Any) -> str:
    return json.dumps(value, indent=2, ensure_ascii=False, sort_keys=True)


def _nested(value: list) -> bool:
    return any(isinstance(x, (list, dict)) for x in value)


def _details(value: Any, limit: int = _DETAILS_LIMIT) -> str:
    """A detector's details for a reader: JSON with flat lists on one line, cut at ``limit`` characters.

    The findings keep everything; pages of coordinates help no reader.
    """

    def fmt(v: Any, depth: int) -> str:
        pad = "  " * depth
        if isinstance(v, dict) and v:
            items = [f"{pad}  {json.dumps(k, ensure_ascii=False)}: {fmt(x, depth + 1)}" for k, x in v.items()]
            return "{\n" + ",\n".join(items) + f"\n{pad}}}"
        if isinstance(v, list) and any(isinstance(x, dict) or isinstance(x, list) and _nested(x) for x in v):
            return "[\n" + ",\n".join(f"{pad}  {fmt(x, depth + 1)}" for x in v) + f"\n{pad}]"
        return json.dumps(v, ensure_ascii=False)

    text = fmt(value, 0)
    if len(text) > limit:
        text = text[:limit] + f"\n... ({len(text) - limit:,} more characters; all of them are in findings.json)"
    return text


def _compact(value: Any) -> str:
    return json.dumps(value, ensure_ascii=False, sort_keys=True, separators=(", ", ": "))


def _environment() -> Environment:
    # The project's own templates: trusted, but autoescaped like everything else.
    env = Environment(loader=FunctionLoader(template_text), autoescape=True, undefined=StrictUndefined,
                      trim_blocks=True, lstrip_blocks=True)
    env.filters.update(num=_num, pretty=_pretty, details=_details, compact=_compact, utc=_utc_text, visible=visible)
    return env


def _camera_rows(exif: ExifSummary) -> list[tuple[str, str]]:
    rows: list[tuple[str, str | None]] = [
        ("Make", exif.make),
        ("Model", exif.model),
        ("Lens", " ".join(v for v in (exif.lens_make, exif.lens_model) if v) or None),
    ]
    if exif.focal_length_mm is not None or exif.focal_length_35mm is not None:
        focal = f"{exif.focal_length_mm:g} mm" if exif.focal_length_mm is not None else "not recorded"
        if exif.focal_length_35mm:
            focal += f" ({exif.focal_length_35mm:g} mm in 35 mm film)"
        rows.append(("Focal length", focal))
    rows += [("Date/time original", exif.datetime_original), ("Date/time (file)", exif.datetime),
             ("Software", exif.software)]
    if exif.exif_image_width and exif.exif_image_height:
        rows.append(("EXIF image size", f"{exif.exif_image_width} × {exif.exif_image_height}"))
    if exif.gps is not None:
        parts = []
        if exif.gps.latitude is not None and exif.gps.longitude is not None:
            parts.append(f"{exif.gps.latitude:.6f}°, {exif.gps.longitude:.6f}° (WGS-84 as recorded)")
        if exif.gps.altitude_m is not None:
            parts.append(f"altitude {exif.gps.altitude_m:.1f} m")
        rows.append(("GPS", "; ".join(parts) or "present but incomplete"))
    return [(k, v) for k, v in rows if v]


def command_line(findings: Findings, photo: Path) -> str:
    """The ``forensics analyze`` command that reproduces the recorded findings (to OUT), one option per line.

    ``photo`` is the evidence file as read: where its name holds bytes that
    are not UTF-8, ``findings.evidence.path`` shows them as text and only
    bash's ``$'...'`` escapes name the file itself.
    """
    p = findings.parameters
    options: list[tuple[str, str]] = [
        ("--out", "OUT"), ("--format", "json"),
        ("--detectors", ",".join(p.get("detectors") or [])),
        ("--fusion", str(p.get("fusion"))), ("--timeout", f"{p.get('timeout_s'):g}"),
        ("--max-pixels", str(p.get("max_pixels"))), ("--isolation", str(p.get("isolation"))),
    ]
    for flag, key in (("--case-id", "case_id"), ("--examiner", "examiner"), ("--calibration", "calibration"),
                      ("--reference", "reference")):
        if p.get(key):
            options.append((flag, str(p[key])))
    # A detector that did not run (skipped) ran with no parameters; its defaults are its version's.
    skipped = {f.name for f in findings.detectors if f.status is Status.SKIPPED}
    for det, params in sorted((p.get("detector_params") or {}).items()):
        if det in skipped:
            continue
        for key, value in sorted(params.items()):
            options.append(("--param", f"{det}.{key}={json.dumps(value, separators=(',', ':'))}"))
    lines = [f"forensics analyze {_shell_quote(str(photo))}"]
    lines += [f"{flag} {_shell_quote(value)}" for flag, value in options]
    return " \\\n    ".join(lines)


def _shell_quote(text: str) -> str:
    """POSIX quoting, or bash's ``$'...'`` with escapes when the text holds characters a page cannot show."""
    if visible(text) == text:
        return shlex.quote(text)
    return "$'" + visible(text.replace("\\", "\\\\").replace("'", "\\'")) + "'"


def _where(findings: Findings, evidence: Evidence, host: PluginHost | None) -> dict[str, Any]:
    """Page 1's picture: the photo with the flagged pixels of every detector that found something outlined.

    The maps come from each detector's ``localize``, the same maps
    ``forensics validate`` scores against true masks, for the detectors
    :func:`.wording.found_something` names; a detector colours its outline
    by its row's position, so that page 1's table is the legend.
    """
    shape = tuple(evidence.pixels.shape[:2])
    masks, flagged = [], []
    for index, finding in enumerate(findings.detectors):
        if host is None or not wording.found_something(finding, findings.verdict):
            continue
        mask = localise_map(host, finding, shape)
        if mask is not None and mask.any():
            masks.append((index, mask))
            flagged.append(finding.name)
    data = images.where_figure(evidence.pixels, masks)
    return {"src": images.data_url(data, "image/jpeg"), "flagged": flagged,
            "colours": {findings.detectors[i].name: i % len(images.WHERE_COLOURS) for i, _ in masks},
            # The shipped record is read only when the caption states it: for a photo with something outlined.
            "validated": _where_validated(flagged) if flagged else ""}


def _where_validated(flagged: list[str]) -> str:
    """How well the Where map and the flagged detectors' maps found forged pixels in the shipped realistic record.

    Empty when no such record is shipped or it predates the Where map's
    scores (pixel F1, :mod:`forensics_core.validation.record`).
    """
    try:
        record = shipped_record(SHIPPED_REALISTIC)
    except (OSError, ValueError, KeyError, TypeError):
        return ""
    where = record.method(VERDICT) if record is not None else None
    if where is None or where.localisation is None or where.localisation.f1_mean is None:
        return ""
    own = [(n, m.localisation) for n in flagged if (m := record.method(n)) is not None and m.localisation]
    each = "; " + ", ".join(f"{n}'s own map {loc.f1_mean:.2f}" for n, loc in own) if own else ""
    return (f"On {where.localisation.n} forgeries with known masks made from real photos (the realistic "
            f"validation record), this map's mean pixel F1 was {where.localisation.f1_mean:.2f}{each} "
            f"(1 outlines exactly the forged pixels).")


def _summary(findings: Findings) -> dict[str, Any]:
    verdict = findings.verdict
    strength = wording.strength(verdict)
    roles = {c.detector: c for c in verdict.contributions}

    def role(name: str) -> dict[str, str]:
        c = roles.get(name)
        if c is None:
            return {"role": "", "role_words": "not stated by the policy", "adjusted_p": "—"}
        return {"role": c.role.value.replace(" ", "-"), "role_words": wording.ROLE_WORDS[c.role],
                "adjusted_p": _num(c.adjusted_p)}

    rows = [
        {"name": f.name, "version": f.version, "status": f.status.value, "status_words": wording.STATUS_WORDS[f.status],
         "score": _num(f.score), "p_value": _num(f.p_value), "nfa": _num(f.nfa), "summary": f.summary, "error": f.error,
         "lr": "—" if f.log10_lr is None else wording.lr_text(f.log10_lr),
         "sentence": wording.row_sentence(f), **role(f.name)}
        for f in findings.detectors
    ]
    reading = {
        "consistent": "No detector's test rejected its null hypothesis at the stated level. That is no evidence that "
                      "the photo is an original: the detectors look for specific traces only.",
        "inconsistent": "At least one detector found a trace that is unlikely in an original photo at the stated level. "
                        "A rejection says how unusual the trace is among originals, not how strongly it supports "
                        "manipulation (the statement above does), nor who altered the photo, how, or why.",
        "inconclusive": "The detectors could not test the photo (too little of their trace, or failures); the screen "
                        "says nothing for or against manipulation.",
    }[verdict.label.value]
    if verdict.policy == LR_POLICY:
        reading = ("Under this policy the screen is the fused likelihood ratio compared with thresholds fixed in "
                   "advance; the statement above gives its value.")
    lr_summary = _lr_summary(verdict, findings.detectors)
    # One line per kind of processing: two detectors that see one lens correction in two traces state one fact.
    processing: list[dict[str, Any]] = []
    for f in findings.detectors:
        if (p := Processing.from_finding(f)) is None:
            continue
        seen = next((q for q in processing if q["kind"] == p.kind), None)
        if seen is None:
            processing.append({"detectors": [f.name], "kind": p.kind, "description": p.description})
        else:
            seen["detectors"].append(f.name)
    sources = [{"detector": f.name, "hp": a.hp, "hd": a.hd, "basis": a.basis, "lr": wording.lr_text(a.log10_lr),
                "verbal": verbal(a.log10_lr, "the first", "the second")}
               for f in findings.detectors if (a := SourceAttribution.from_finding(f)) is not None]
    return {
        "statement": wording.statement(verdict),
        "screening": wording.screening(verdict),
        "processing": processing,
        "sources": sources,
        "tension": _tension(verdict, lr_summary, rows),
        "strength": strength,
        "explanation": verdict.explanation,
        "reading": reading,
        "policy": verdict.policy,
        "method": verdict.method,
        "rows": rows,
        "scale": wording.scale() if strength.graded else (),
        "lr": lr_summary,
    }


def _tension(verdict: Verdict, lr_summary: dict[str, Any] | None, rows: Sequence[dict[str, Any]]) -> str | None:
    """What the report says when the screen and the likelihood ratio point different ways, else None.

    The screen tests each detector's trace against a level fixed in advance
    and leaves out detectors that state no p-value; the likelihood ratio
    weighs every calibrated detector. A screen that rejected nothing beside
    support for Hp (or a rejection beside support for Hd) would otherwise
    read as one answer when there are two.
    """
    lr = verdict.likelihood_ratio
    if verdict.policy == LR_POLICY or lr is None or lr.log10_lr is None or lr_summary is None:
        return None
    side = supports(lr.log10_lr)
    carriers = lr_summary["contributed"]
    if verdict.label.value == "consistent" and side > 0:
        untested = ", ".join(r["name"] for r in rows if r["role"] == "advisory")
        left_out = f" ({untested} state none and are left out of it)" if untested else ""
        return (f"The screen and the statement point different ways. No detector's test rejected an original at the "
                f"stated level, yet the calibrated likelihood ratio gives {lr.verbal}. The screen counts only "
                f"detectors that state a p-value{left_out}; the likelihood ratio weighs every calibrated detector. "
                f"Read the sections of the detectors that carry the likelihood ratio ({carriers}).")
    if verdict.label.value == "inconsistent" and side < 0:
        return (f"The screen and the statement point different ways. A detector's test rejected an original at the "
                f"stated level, yet the calibrated likelihood ratio gives {lr.verbal}. A rejection says how "
                f"unusual the trace is among originals, not how much more probable it is after manipulation; on the "
                f"calibration data, findings like these were more probable in originals. Read the section of the "
                f"detector that drove the screen before relying on it.")
    return None


def _lr_summary(verdict, detectors) -> dict[str, Any] | None:
    """Page 1's evaluative statement: propositions, the fused LR in words, who contributed, the data behind it."""
    lr = verdict.likelihood_ratio
    if lr is None:
        return None
    cal = lr.calibration
    sentence = None
    if lr.log10_lr is not None:
        sentence = (f"The findings are {wording.lr_words(lr.log10_lr)} if {lr.hp} (Hp) than if {lr.hd} (Hd): "
                    f"likelihood ratio {10.0 ** lr.log10_lr:.3g}, {lr.verbal}.")
    cllr = cal.get("cllr_fused")
    # A detector whose LR is not 1 but within the scale's "no support" band
    # (a calibrator with no measured power gives such LRs on every photo)
    # is named apart, so that the list says who carries the evidence.
    own = {d.name: d.log10_lr for d in detectors}
    supporting = [n for n in lr.contributed if supports(own.get(n))]
    slight = [n for n in lr.contributed if n not in supporting]
    return {
        "hp": lr.hp, "hd": lr.hd, "sentence": sentence, "verbal": lr.verbal,
        "contributed": ", ".join(supporting) or "none",
        "slight": ", ".join(slight),
        "band": f"between 1/{WEAK_SUPPORT_LR:g} and {WEAK_SUPPORT_LR:g}",
        "threshold": f"{WEAK_SUPPORT_LR:g}",
        "uncalibrated": ", ".join(lr.uncalibrated),
        "experimental": ", ".join(lr.experimental),
        # Only calibrations that name experimental detectors state the bar (a calibration file made before has none).
        "min_auc": "" if cal.get("min_fusion_auc") is None else f"{cal['min_fusion_auc']:g}",
        "relevance": lr.relevance,
        "performance": (f"Cross-validated on that data ({cal.get('cross_validation')}), the fused LR's cost Cllr is "
                        f"{cllr:.2f} (0 for perfect evidence, 1 for none){_by_record(cal)}." if cllr is not None
                        else ""),
    }


def _by_record(cal: dict[str, Any]) -> str:
    """The fused Cllr per calibration record, when there are several (found photos and generated ones differ)."""
    parts = cal.get("cllr_fused_by_record") or {}
    if len(parts) < 2:
        return ""
    return ": " + ", ".join(f"{v:.2f} on the {k} record" for k, v in parts.items() if v is not None)


def _error_rates(findings: Findings, options: ReportOptions) -> ErrorRates:
    if options.validation is not None:
        return given_error_rates(findings, options.validation,
                                 options.validation_source or "a validation record given by the examiner")
    return shipped_error_rates(findings)


def _stylesheet(paper: str) -> str:
    if paper not in PAPER_SIZES:
        raise ValueError(f"paper must be one of {', '.join(PAPER_SIZES)}")
    return template_text("report.css") + f"\n@page {{ size: {PAPER_SIZES[paper]}; }}\n"


def _csp(css: str) -> str:
    """No scripts, no fetches, images only inline, and only this exact stylesheet."""
    digest = base64.b64encode(hashlib.sha256(css.encode("utf-8")).digest()).decode("ascii")
    return ("default-src 'none'; script-src 'none'; object-src 'none'; img-src data:; "
            f"style-src 'sha256-{digest}'; font-src 'none'; connect-src 'none'; base-uri 'none'; form-action 'none'")


def render_html(findings: Findings, evidence: Evidence, signature: SignatureInfo, options: ReportOptions,
                host: PluginHost | None = None, sections: Sequence[DetectorSection] | None = None) -> RenderedReport:
    """Render ``report.html``.

    Parameters
    ----------
    findings, evidence
        The run to report and the evidence it examined.
    signature : SignatureInfo
        Examiner and certificate for the signature block.
    options : ReportOptions
    host : PluginHost, optional
        Plugins asked for their detector sections; without it every
        detector gets the generic section.
    sections : sequence of DetectorSection, optional
        Already built sections (otherwise built here).
    """
    # A plugin's section is held to the run's --timeout, as its analysis was.
    timeout = findings.parameters.get("timeout_s")
    built = (list(sections) if sections is not None
             else sections_for(host, findings.detectors, evidence, jobs=options.jobs,
                               timeout_s=float(timeout) if isinstance(timeout, (int, float)) and timeout > 0 else None))
    css = "\n".join([_stylesheet(options.paper)] + [s.css for s in built if s.css])
    thumbnail = images.thumbnail_jpeg(evidence.thumbnail)
    ev = findings.evidence
    context = {
        "csp": _csp(css),
        "css": Markup(css),  # the project's own stylesheet, not evidence data
        "tool": findings.tool,
        "created": findings.created,
        "schema_version": findings.schema_version,
        "report_date": options.report_date or datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z"),
        "case_id": findings.parameters.get("case_id") or NOT_GIVEN,
        "exhibit_id": options.exhibit_id or NOT_GIVEN,
        "evidence": ev,
        "references": findings.references,
        "orientation": (_ORIENTATIONS.get(ev.orientation, str(ev.orientation)) + "; recorded, not applied"
                        if ev.orientation is not None else "not recorded"),
        "camera_rows": _camera_rows(ev.exif),
        "photo_src": images.data_url(images.preview(evidence.pixels, images.WHERE_SIDE), "image/jpeg"),
        "thumbnail_src": images.data_url(thumbnail, "image/jpeg") if thumbnail else None,
        "thumbnail_note": (f"The EXIF data names a thumbnail, but it could not be read: {evidence.thumbnail.error}."
                           if evidence.thumbnail is not None else "The file carries no embedded thumbnail."),
        "summary": _summary(findings),
        "where": _where(findings, evidence, host),
        "sections": built,
        "status_words": wording.STATUS_WORDS,
        "parameters": findings.parameters,
        "environment": findings.environment,
        "report_packages": _report_packages(),
        "plugins": findings.plugins,
        "detectors": findings.detectors,
        "command_line": command_line(findings, evidence.path),
        "signature": signature,
        "raw_tags": ev.exif.raw,
        "metadata_groups": _metadata_groups(ev.metadata),
        "metadata_file": METADATA_CSV,
        "extra_metadata": ev.extra_metadata,
        "error_rates": _error_rates(findings, options),
    }
    html = _environment().get_template("report.html.j2").render(context)
    return RenderedReport(html=html, sections=built, files={METADATA_CSV: _metadata_csv(ev)})


def _metadata_csv(ev) -> bytes:
    """Every metadata tag of the evidence as a table: ExifTool's by group, else the raw EXIF tags."""
    if ev.metadata:
        return csv_bytes(["group", "tag", "value"], [[t.group, t.name, t.value] for t in ev.metadata])
    return csv_bytes(["ifd", "tag", "name", "value"], [[t.ifd, f"0x{t.tag:04x}", t.name, t.value] for t in ev.exif.raw])


def _metadata_groups(tags) -> list[tuple[str, list]]:
    """ExifTool's tags by family-1 group, groups in the order ExifTool met them."""
    groups: dict[str, list] = {}
    for t in tags:
        groups.setdefault(t.group, []).append(t)
    return list(groups.items())


def render_pdf(report: RenderedReport, layout: LayoutProcess | None = None) -> bytes:
    """The report's PDF, laid out by ``layout`` (a warm process of its own) or else here.

    Refused URLs are added to ``report.refused_urls``.
    """
    if layout is not None:
        pdf, refused = layout.lay_out(report.html)
    else:
        from .pdf import lay_out

        pdf, refused = lay_out(report.html)
    report.refused_urls.extend(refused)
    return pdf
