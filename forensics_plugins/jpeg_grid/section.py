"""The JPEG grid section of the evidence report."""

from __future__ import annotations

from importlib.resources import files
from typing import Any

from forensics_core import DetectorFinding, Evidence, Status
from forensics_core.report import Figure, ReportSection, Table

from .spec import REFERENCES
from .figures import map_png, vote_map_png
from .nfa import nfa_text

_STAGE_WORDS = {
    "foreign": "own grid",
    "missing": "main grid missing",
    "resampled": "first grid moved by a radial warp (processing)",
    "cropped": "first grid moved by a crop (processing)",
    "radial step": "first grid moved one pixel along its radius (possible processing)",
}


def _region_rows(regions: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [{
        "id": r["id"], "grid": f"({r['grid'][0]}, {r['grid'][1]})", "stage": _STAGE_WORDS.get(r["stage"], r["stage"]),
        "x": f"{r['bbox_px'][0]}-{r['bbox_px'][2]}", "y": f"{r['bbox_px'][1]}-{r['bbox_px'][3]}",
        "area": f"{100 * r['area_fraction']:.1f} %", "pixels": r["pixels"],
        "density": f"{100 * r['density']:.1f} %", "nfa": nfa_text(r["log10_nfa"]),
        "css": "line-flagged" if r["meaningful"] else "",
        "verdict": ("explained by the radial warp" if r["stage"] == "resampled" else
                    "explained by the crop" if r["stage"] == "cropped" else
                    "a lens correction's step, too few to establish the warp" if r["stage"] == "radial step" else
                    "meaningful" if r["meaningful"] else "not meaningful"),
    } for r in regions]


def _lattice_context(lattice: dict[str, Any] | None) -> dict[str, Any] | None:
    """What the report says of the quantisation-lattice test (:mod:`.lattice`), or None when it did not run."""
    if lattice is None:
        return None
    steps = [q for row in lattice.get("steps", []) for q in row if q > 0]
    return {
        "applicable": lattice["applicable"],
        "reason": lattice.get("reason", ""),
        "jpeg": lattice["reading"].startswith("earlier"),
        "origin": f"({lattice['origin'][0]}, {lattice['origin'][1]})",
        "n_frequencies": lattice.get("n_frequencies", 0),
        "steps": f"{min(steps)}-{max(steps)}" if steps else "",
        "testable": lattice.get("testable_blocks", 0),
        "flagged": lattice.get("flagged_blocks", 0),
        "clipped": lattice.get("clipped_blocks", 0),
    }


SHOWN_REGIONS = 3
"""Regions listed on the page; all those listed in the finding are in the CSV file."""


def _tables(details: dict[str, Any]) -> dict[str, Table]:
    """The share of votes of each of the 64 grid origins, and every region listed, with its box and test.

    The tiles of each region stay in ``findings.json`` (``details.regions[].tiles_rle``).
    """
    tables = {}
    if "vote_shares" in details:
        main = details["main_grid"]["origin"]
        tables["votes"] = Table(["dx", "dy", "share", "main"],
                                [[dx, dy, share, [dx, dy] == main]
                                 for dy, row in enumerate(details["vote_shares"]) for dx, share in enumerate(row)],
                                "the share of the votes cast for each of the 64 grid origins")
    if details.get("regions"):
        rows = [[r["id"], r["grid"][0], r["grid"][1], row["stage"], *r["bbox_px"], r["area_fraction"],
                 r.get("area_px"), r["pixels"], r["density"], r["log10_nfa"], r["meaningful"], row["verdict"]]
                for r, row in zip(details["regions"], _region_rows(details["regions"]))]
        tables["regions"] = Table(["region", "dx", "dy", "found_by", "x0_px", "y0_px", "x1_px", "y1_px",
                                   "area_fraction", "area_px", "voting_pixels", "density", "log10_nfa", "meaningful",
                                   "verdict"], rows, "every region listed: its grid, box, votes and NFA")
    return tables


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one JPEG grid finding: map, grid, regions, test, method and limitations.

    The 64 origins' votes and every region listed go to CSV files beside the
    report; the page lists the first regions.
    """
    details = finding.details
    main = details["main_grid"]
    regions = details.get("regions", [])
    meaningful = [r for r in regions if r["meaningful"]]
    thresholds = details["thresholds"]
    if finding.status is not Status.OK:
        decision = "no decision: the photo carries no significant JPEG grid and no region votes for one"
    elif meaningful:
        decision = (f"{len(meaningful)} region(s) compressed on another grid or missing the main grid"
                    if main["significant"] else f"{len(meaningful)} region(s) compressed on a grid the rest lacks")
    else:
        decision = "no region departs from the main grid"
    context = {
        "ok": finding.status is Status.OK,
        "significant": main["significant"],
        "main": main,
        "main_nfa": nfa_text(main["log10_nfa"]),
        "cropped": details.get("cropped", False),
        "quality": details.get("jpeg_quality_estimate"),
        "luminance_note": details["luminance"]["note"],
        "regions": _region_rows(regions)[:SHOWN_REGIONS],
        "n_regions": len(regions),
        "n_meaningful": len(meaningful),
        "thresholds": thresholds,
        "n_tests": nfa_text(details["log10_n_tests"]) if "log10_n_tests" in details else None,
        "min_region_px": details.get("min_region_px"),
        "missing_tested": details.get("missing_tested", False),
        "lattice": _lattice_context(details.get("lattice")),
        "decision": decision,
        "references": list(REFERENCES),
    }
    figures = {}
    if details.get("map") and finding.status is Status.OK:
        figures["map"] = Figure(map_png(evidence.pixels, details), "image/png",
                                "The photo with the regions whose pixels vote for a JPEG grid other than the main "
                                "one (labelled with its origin (dx, dy)) or lack the main grid (\"no main grid\"), "
                                "numbered as in the table: filled red, meaningful (NFA below the threshold); orange "
                                "outline, the strongest candidate when none is.")
    if details.get("map"):
        figures["votes"] = Figure(vote_map_png(details), "image/png",
                                  "Share of the votes cast that go to the most voted grid, per block of the photo "
                                  "(black 0 %, white 100 %; dark blue: no vote cast, as on borders and in flat or "
                                  "saturated areas), with the regions outlined. A pasted region whose own grid shows "
                                  "through is dark here.")
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="JPEG block grid", template=template, context=context, figures=figures,
                         tables=_tables(details))
