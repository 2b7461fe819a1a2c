"""The metadata section of the evidence report."""

from __future__ import annotations

from importlib.resources import files
from typing import Any

from forensics_core import DetectorFinding, Evidence
from forensics_core.report import Figure, ReportSection, Table

from .detector import thresholds
from .spec import DEFAULT_PARAMS, REFERENCES
from .figures import lens_plot_svg, thumbnail_png
from .real_rates import corpus_sentence, rate_sentence
from .thumbnail import accepted, compare, luma_of


def _num(value: float | None, fmt: str) -> str:
    return "–" if value is None else format(value, fmt)


def _lens_rows(lens: dict[str, Any]) -> list[tuple[str, str]]:
    rows = [
        ("camera (lensfun)", lens.get("camera") or "–"),
        ("lens (lensfun)", lens.get("lens") or "–"),
        ("lens identified by", lens.get("matched_by") or "–"),
        ("focal length (EXIF)", _num(lens.get("focal_mm"), "g") + " mm" if lens.get("focal_mm") else "–"),
        ("lensfun model and terms", f"{lens['model']} {lens['terms']}" if lens.get("model") else "–"),
        ("crop factor: camera / calibration",
         f"{_num(lens.get('camera_crop'), '.3f')} / {_num(lens.get('calibration_crop'), '.3f')}"),
        ("calibration aspect ratio", _num(lens.get("calibration_aspect"), ".3f")),
        ("lensfun radius per normalised radius", _num(lens.get("scale"), ".4f")),
        ("predicted k1 (two-term fit)", _num(lens.get("k1_predicted"), "+.4f")),
        ("predicted k2 (two-term fit)", _num(lens.get("k2_predicted"), "+.4f")),
        ("what two terms cannot follow (RMS)",
         "–" if lens.get("fit_rms_px") is None else f"{lens['fit_rms_px']:.2f} px"),
        ("predicted k1 (one-term fit, for reference)", _num(lens.get("k1_predicted_one_term"), "+.4f")),
        ("measured k1 ± standard error",
         f"{_num(lens.get('k1_measured'), '+.4f')} ± {_num(lens.get('k1_measured_stderr'), '.4f')}"),
        ("measured k2 ± standard error",
         f"{_num(lens.get('k2_measured'), '+.4f')} ± {_num(lens.get('k2_measured_stderr'), '.4f')}"),
        ("difference in k1, z", f"{_num(lens.get('difference'), '+.4f')}, z = {_num(lens.get('z'), '+.2f')}"),
        ("tolerance, critical z",
         f"{lens.get('tolerance')}, {_num(lens.get('z_crit'), '.2f')} (two-sided, alpha {lens.get('alpha')})"),
        ("outcome", lens.get("outcome", "–") + (f" ({lens['reason']})" if lens.get("reason") else "")),
    ]
    return rows


def _lens_numbers(lens: dict[str, Any]) -> str | None:
    """The lens comparison's key numbers in a clause; every row of it is in the CSV file."""
    if lens.get("k1_predicted") is None:
        return None
    text = (f"at the EXIF focal length ({_num(lens.get('focal_mm'), 'g')} mm) it predicts k1 = "
            f"{lens['k1_predicted']:+.4f} (two-term fit)")
    if lens.get("k1_measured") is None:
        return text
    return (f"{text}; the lens detector measured {lens['k1_measured']:+.4f} ± "
            f"{_num(lens.get('k1_measured_stderr'), '.4f')}, a difference of {_num(lens.get('difference'), '+.4f')} "
            f"(z = {_num(lens.get('z'), '+.2f')} against the tolerance {lens.get('tolerance')}, critical z "
            f"{_num(lens.get('z_crit'), '.2f')})")


_QUIET = ("consistent", "not available")
"""Outcomes the page names in one line; their observations are in the CSV file."""


def _tables(checks: list[dict[str, Any]], lens_rows: list[tuple[str, str]], lens: dict[str, Any]) -> dict[str, Table]:
    """Every check with its observation and false-alarm rate, and every row of the lens comparison."""
    tables = {"checks": Table(["check", "title", "outcome", "observation", "false_alarm_rate"],
                              [[c.get("id"), c.get("title"), c.get("outcome"), c.get("observation"), c.get("rate")]
                               for c in checks], "every check with its observation and false-alarm rate")}
    if lens.get("camera"):
        tables["lens"] = Table(["quantity", "value"], [list(row) for row in lens_rows],
                               "the lens comparison in full")
    return tables


def _figures(finding: DetectorFinding, evidence: Evidence) -> dict[str, Figure]:
    figures: dict[str, Figure] = {}
    params = {**DEFAULT_PARAMS, **finding.parameters}
    limits = thresholds(params)
    if finding.details.get("thumbnail", {}).get("present"):
        thumb = accepted(evidence.thumbnail, limits)
        if thumb is not None:
            cmp = compare(evidence.pixels, luma_of(thumb), limits.aspect_tolerance, limits.blur_px,
                          limits.change_threshold)
            figures["thumbnail"] = Figure(
                thumbnail_png(evidence.pixels, thumb, cmp, limits.change_threshold), "image/png",
                "Left: the stored image, reduced; middle: the thumbnail embedded in the EXIF (IFD1), enlarged, "
                "with its picture area in blue; right: their difference after matching the part of the image the thumbnail "
                "shows, blurring and fitting the thumbnail's tone curve, red "
                "above the change threshold, the largest differing region in orange. Orientation is applied to "
                "neither.")
    lens = finding.details.get("lens", {})
    if lens.get("k1_predicted") is not None:
        figures["lens"] = Figure(
            lens_plot_svg(lens), "image/svg+xml",
            "Relative radial displacement against radius: lensfun's calibration of the named lens (solid), the "
            "two-term model fitted to it (dashed) and, when the lens detector measured it, the photo's own (green, "
            "95% band for k1).")
    return figures


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one metadata finding: the checks, the thumbnail, the lens comparison, method and limitations.

    Every check and the whole lens comparison go to CSV files beside the
    report; the page gives the checks that need explaining and the lens's key numbers.
    """
    details = finding.details
    thumb = details.get("thumbnail", {})
    checks = [{**c, "rate": rate_sentence(str(c.get("id")))} for c in details.get("checks", [])]
    lens_rows = _lens_rows(details.get("lens", {}))
    context = {
        "checks": [c for c in checks if c.get("outcome") not in _QUIET],
        "quiet": {outcome: [c["title"] for c in checks if c.get("outcome") == outcome] for outcome in _QUIET},
        "n_applicable": details.get("n_applicable", 0),
        "n_suspicious": details.get("n_suspicious", 0),
        "score_text": "not computed" if finding.score is None else f"{finding.score:.2f}",
        "thumbnail": thumb,
        "thumb_thresholds": thumb.get("thresholds", {}),
        "quantisation": details.get("quantisation"),
        "lens": details.get("lens", {}),
        "lens_numbers": _lens_numbers(details.get("lens", {})),
        "datetime_tolerance_s": finding.parameters.get("datetime_tolerance_s", DEFAULT_PARAMS["datetime_tolerance_s"]),
        "own_table_makers": ", ".join(finding.parameters.get("own_table_makers", DEFAULT_PARAMS["own_table_makers"])),
        "rates_corpus": corpus_sentence(),
        "references": list(REFERENCES),
    }
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Metadata", template=template, context=context, figures=_figures(finding, evidence),
                         tables=_tables(checks, lens_rows, details.get("lens", {})))
