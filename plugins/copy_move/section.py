"""The copy_move section of the evidence report."""

from __future__ import annotations

from importlib.resources import files

from forensics_core import DetectorFinding, Evidence
from forensics_core.report import Figure, ReportSection

from .detector import sheared, stretched
from .spec import GRAIN, REFERENCES
from .figures import DIFFERENCE_GAIN, overlay_png, regions_png


def _scale(record: dict) -> str:
    """The scale cell: one scale for a similarity, along x and y for a stretched (affine) alignment."""
    if stretched(record):
        return "{:.3f} × {:.3f}".format(*record["scale_xy"])
    return f"{record['scale']:.3f}"


def report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection:
    """The section for one copy_move finding: the overlay, the candidate copies, the method and its limits."""
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
        "work_scale": d.get("work_scale"), "rows": rows, "params": finding.parameters,
        "log10_lr": finding.log10_lr, "references": list(REFERENCES), "opencv": d.get("opencv"),
    }
    template = files(__package__).joinpath("templates/section.html.j2").read_text(encoding="utf-8")
    return ReportSection(title="Copy-move (cloned regions)", template=template, context=context, figures=figures)
