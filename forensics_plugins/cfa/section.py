"""The CFA section of the evidence report."""

from __future__ import annotations

from importlib.resources import files
from typing import Any

from forensics_core import PROCESSING_KEY, DetectorFinding, Evidence, Status
from forensics_core.report import Figure, ReportSection, Table

from .spec import REFERENCES
from .figures import map_png

_KIND_WORDS = {"diagonal": "green on the other diagonal", "red_blue": "red and blue swapped"}

SHOWN_REGIONS = 5
"""Regions listed on the page; all of them are in the CSV file."""


def _p_text(log10_p: float | None) -> str:
    if log10_p is None:
        return "–"
    return f"{10 ** log10_p:.2g}" if log10_p > -300 else f"10^{log10_p:.0f}"


def _rate_row(name: str, rate: dict[str, Any] | None) -> dict[str, Any] | None:
    if not rate or not rate.get("votes"):
        return None
    lo, hi = rate["ci95"]
    return {"name": name, "agree": rate["agree"], "votes": rate["votes"], "rate": f"{rate['rate']:.3f}",
            "ci": f"{lo:.3f} – {hi:.3f}", "p": _p_text(rate["log10_p"])}


def _power_text(power: dict[str, Any] | None) -> str | None:
    if not power or power.get("fraction") is None:
        return None
    return f"{100 * power['fraction']:.1f}% of the photo ({power['side_blocks']} x {power['side_blocks']} blocks)"


def _region_rows(regions: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [{
        "id": r["id"], "kind": _KIND_WORDS.get(r["kind"], r["kind"]),
        "area": f"{100 * r['area_fraction']:.1f}%", "bbox": "{} , {} – {} , {}".format(*r["bbox_px"]),
        "nfa": _p_text(r["log10_nfa"]), "votes": f"{r['votes_against']} / {r['votes']}",
        "pattern": r.get("pattern") or "–",
    } for r in regions]


REGION_COLUMNS = ["region", "status", "disagreement", "area_fraction", "n_blocks", "x0_px", "y0_px", "x1_px", "y1_px",
                  "window_x0_px", "window_y0_px", "window_x1_px", "window_y1_px", "log10_nfa", "votes_against",
                  "votes", "null_rate", "ring_agree", "ring_votes", "pattern"]


def regions_table(details: dict[str, Any]) -> Table | None:
    """Every region, flagged or set aside, with its box, test and votes; None when there is none.

    The blocks of each region stay in ``findings.json`` (``details.regions[].blocks``).
    """
    listed = [("flagged", r) for r in details.get("regions", [])]
    listed += [("set aside", r) for r in details.get("regions_set_aside", [])]
    listed += [("explained by the mosaic's drift", r) for r in details.get("regions_explained", [])]
    if not listed:
        return None
    rows = [[r["id"], status, _KIND_WORDS.get(r["kind"], r["kind"]), r["area_fraction"], r.get("n_blocks"),
             *r["bbox_px"], *r.get("window_px", [None] * 4), r["log10_nfa"], r["votes_against"], r["votes"],
             r.get("null_rate"), r.get("ring_agree"), r.get("ring_votes"), r.get("pattern")] for status, r in listed]
    return Table(REGION_COLUMNS, rows, "every region whose votes disagree with the photo's phase: box, NFA, votes")


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one CFA finding: map, numbers, the test, method and limitations.

    The regions go to ``cfa-regions.csv`` beside the report; the page lists the first few.
    """
    d = finding.details
    regions = d.get("regions", [])
    thresholds = d.get("thresholds", {})
    pattern = d.get("pattern") or {}
    # After a lens correction each block is judged against the phase the correction gave it.
    phase = ("the phase the lens correction gave each block" if "mosaic" in d.get(PROCESSING_KEY, {})
             else "the photo's demosaicing phase")
    if finding.status is not Status.OK:
        decision = "no decision: the photo does not carry enough of the trace"
    elif regions:
        decision = f"{len(regions)} region(s) disagree with {phase}"
    else:
        decision = f"no region disagrees with {phase}"
    power = d.get("power", {})
    context = {
        "reason": d.get("reason"),
        "decision": decision,
        "block_px": d.get("block_px"),
        "grid": d.get("grid"),
        "n_usable": d.get("n_usable"),
        "usable_pct": None if d.get("usable_fraction") is None else f"{100 * d['usable_fraction']:.0f}%",
        "rates": [row for row in (_rate_row("green diagonal", d.get("diagonal")),
                                  _rate_row("red / blue sites", d.get("red_blue"))) if row],
        "trace_alpha": thresholds.get("trace_alpha"),
        "nfa_threshold": thresholds.get("nfa_threshold"),
        "max_detectable_pct": f"{100 * thresholds.get('max_detectable_fraction', 0):.0f}%",
        "n_tests": d.get("n_tests"),
        "min_nfa": _p_text(d.get("min_log10_nfa")) if "min_log10_nfa" in d else None,
        "power_diag": _power_text(power.get("diagonal")),
        "power_rb": _power_text(power.get("red_blue")),
        "pattern": pattern.get("pattern"),
        "pattern_candidate": pattern.get("candidate"),
        "pattern_algorithm": (pattern.get("algorithm") or "").replace("_", "-"),
        "pattern_votes": pattern.get("tile_votes", {}),
        "pattern_tiles": pattern.get("n_tiles"),
        "pattern_p": _p_text(pattern.get("log10_p")) if pattern else None,
        "pattern_alpha": pattern.get("alpha"),
        "regions": _region_rows(regions)[:SHOWN_REGIONS],
        "n_regions": len(regions),
        "n_set_aside": len(d.get("regions_set_aside", [])),
        "n_explained": len(d.get("regions_explained", [])),
        "references": list(REFERENCES),
    }
    figures = {}
    if "shift_votes" in d:
        figures["map"] = Figure(
            map_png(evidence.pixels, d), "image/png",
            f"Each block of {d['block_px']} x {d['block_px']} pixels tinted by the mosaic phase it votes for: clear, "
            "the photo's phase; red, green on the other diagonal; orange, red and blue swapped; grey, no vote. "
            "Detected regions are outlined in cyan and numbered as in the table.")
    table = regions_table(d)
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Colour filter array (demosaicing) consistency", template=template,
                         context=context, figures=figures, tables={"regions": table} if table else {})
