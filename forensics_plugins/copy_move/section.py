"""The copy_move section of the evidence report."""

from __future__ import annotations

from importlib.resources import files
from typing import Any

from forensics_core import DetectorFinding, Evidence
from forensics_core.report import Figure, ReportSection, Table

from .detector import sheared, stretched
from .spec import GRAIN, REFERENCES
from .figures import DIFFERENCE_GAIN, overlay_png, regions_png


def _scale(record: dict) -> str:
    """The scale cell: one scale for a similarity, along x and y for a stretched (affine) alignment."""
    if stretched(record):
        return "{:.3f} × {:.3f}".format(*record["scale_xy"])
    return f"{record['scale']:.3f}"


SHOWN_CANDIDATES = 3
"""Candidate copies listed on the page, the best first; all of them are in the CSV file."""

CANDIDATE_COLUMNS = ["candidate", "best", "found_by", "keypoints", "matches_log10_nfa", "scale", "scale_x", "scale_y",
                     "shear", "rotation_deg", "shift_x_px", "shift_y_px", "matrix_px", "aligned_on", "grain_r",
                     "grain_peak", "lattice_peak_before", "lattice_peak_after", "lattice_peak", "net_peak",
                     "windows", "windows_at_peak", "grain_sigma", "area_px"]


def _tables(d: dict[str, Any]) -> dict[str, Table]:
    """Every candidate copy, the windows whose grain peak marks them, and the matched keypoints they rest on."""
    records = d.get("hypotheses", [])
    if not records:
        return {}
    candidates = [[h["id"], h["id"] == d.get("best"), h.get("found_by"), h["n_inliers"], h.get("matches_log10_nfa"),
                   h["scale"], *(h.get("scale_xy") or [h["scale"], h["scale"]]), h.get("shear"), h["rotation_deg"],
                   *h["translation_px"], str(h.get("matrix_px")), h.get("aligned_on"), h["identity"],
                   h.get("grain_peak"), *(h.get("lattice_peaks") or [None, None]), h.get("lattice_peak"),
                   h.get("net_peak"), h["n_windows"], len(h["identical_windows_px"]), h.get("grain_sigma"),
                   h.get("area_px")] for h in records]
    windows = [[h["id"], *w] for h in records for w in h["identical_windows_px"]]
    matches = [[h["id"], *src, *dst] for h in records
               for src, dst in zip(h.get("source_px", []), h.get("target_px", []))]
    tables = {"candidates": Table(CANDIDATE_COLUMNS, candidates,
                                  "every candidate copy: transform, grain, lattice and net peaks")}
    if windows:
        tables["windows"] = Table(["candidate", "x_px", "y_px", "side_px", "grain_peak"], windows,
                                  "the windows whose grain peak reaches the threshold, per candidate")
    if matches:
        tables["matches"] = Table(["candidate", "source_x_px", "source_y_px", "target_x_px", "target_y_px"], matches,
                                  "the matched points of each candidate, source and target")
    return tables


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one copy_move finding: the overlay, the candidate copies, the method and its limits.

    Every candidate, its windows and its matched keypoints go to CSV files
    beside the report; the page lists the best few.
    """
    d = finding.details
    rows = [{
        "id": h["id"], "found_by": "grain" if h.get("found_by") == GRAIN else "keypoints",
        "inliers": "–" if h["n_inliers"] is None else h["n_inliers"], "scale": _scale(h),
        "nfa": "–" if h.get("matches_log10_nfa") is None else f"{h['matches_log10_nfa']:.0f}",
        "rotation": f"{h['rotation_deg']:.1f}°{sheared(h)}",
        "shift": "{:.0f}, {:.0f}".format(*h["translation_px"]),
        "identity": "–" if h["identity"] is None else f"{h['identity']:.2f}",
        "peak": "–" if h.get("grain_peak") is None else f"{h['grain_peak']:.2f}", "windows": h["n_windows"],
        "lattice": "–" if h.get("net_peak") is None else f"{h['lattice_peak']:.2f}",
        "net": "–" if h.get("net_peak") is None else f"{h['net_peak']:.2f}",
        "identical": len(h["identical_windows_px"]), "best": h["id"] == d.get("best"),
    } for h in d.get("hypotheses", [])]
    rows.sort(key=lambda r: not r["best"])
    figures = {}
    if d.get("best") is not None:
        figures["overlay"] = Figure(
            overlay_png(evidence.luma, d), "image/png",
            "The best candidate copy: matched keypoints joined by yellow lines (for a move found by the grain, the "
            "outlines of the two smooth areas); red, windows of one region whose "
            "grain peak with the other's is "
            f"{finding.parameters.get('identical_window_peak', 0.2)} or more; blue, where they come from under the transform. "
            "Which of the two is the copy cannot be told from the match alone.")
        regions = regions_png(evidence.luma, d)
        if regions is not None:
            figures["regions"] = Figure(
                regions, "image/png",
                "The two regions of the best candidate, enlarged: left (red frame) the region whose windows share "
                "their grain with the other's, middle (blue frame) the other region mapped onto it by the transform, "
                f"right their difference ({DIFFERENCE_GAIN:.0f} times, mid-grey where they are equal). "
                "A copy shows one object twice and differs from its source by the compression's faint grain alone, "
                "over the area the copy covers; two objects in the scene differ in shading, detail and what shows "
                "between their parts. A printed or manufactured pattern (a mesh, wallpaper, tiles, two prints of one "
                "picture) shows as such, and the grain test cannot tell it from a copy.")
    context = {
        "n_keypoints": d.get("n_keypoints"), "n_matches": d.get("n_matches"),
        "n_dense": d.get("n_dense_candidates", 0),
        "work_scale": d.get("work_scale"), "rows": rows[:SHOWN_CANDIDATES], "n_candidates": len(rows),
        "params": finding.parameters, "log10_lr": finding.log10_lr, "references": list(REFERENCES),
        "opencv": d.get("opencv"),
    }
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Copy-move (cloned regions)", template=template, context=context, figures=figures,
                         tables=_tables(d))
