"""Figures of the lens distortion finding for the report.

Both are drawn from the finding's ``details`` alone (plus the photo for the
overlay), so a report can be rebuilt from ``findings.json`` and the evidence.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from typing import Any

import numpy as np
from PIL import ImageDraw, ImageFont

from forensics_core.report import display_image, figure_png

OVERLAY_MAX_SIDE = 1600

# Colour by how far a line departs from the global model (|z|), and red for
# the lines the test flagged, so the figure and the table say the same thing.
COLOURS = {
    "flagged": (220, 30, 30),
    "strong": (245, 150, 20),
    "consistent": (30, 170, 60),
    "uninformative": (120, 140, 230),
}


def line_class(line: Mapping[str, Any]) -> str:
    """Colour class of one line record: flagged, strong (|z| >= 2), consistent or uninformative."""
    if line.get("flagged"):
        return "flagged"
    z = line.get("z")
    if z is None or not line.get("informative", True):
        return "uninformative"
    return "strong" if abs(z) >= 2.0 else "consistent"


def overlay_png(pixels: np.ndarray, details: Mapping[str, Any]) -> bytes:
    """The photo with every extracted line drawn, numbered and coloured by its consistency.

    Parameters
    ----------
    pixels : ndarray, shape (H, W) or (H, W, C)
        The evidence's stored grid.
    details : mapping
        The finding's details (``lines`` with ``points_px`` in pixels).

    Returns
    -------
    bytes
        PNG, longest side at most :data:`OVERLAY_MAX_SIDE` pixels.
    """
    img, factor = display_image(pixels, OVERLAY_MAX_SIDE, 0.6, 40)
    draw = ImageDraw.Draw(img)
    width = max(2, round(max(img.size) / 400))
    font = ImageFont.load_default(size=max(12, round(max(img.size) / 55)))
    for line in details.get("lines", []):
        pts = np.asarray(line["points_px"], dtype=np.float64) * factor
        colour = COLOURS[line_class(line)]
        draw.line([tuple(p) for p in pts], fill=colour, width=width)
        x, y = pts[len(pts) // 2]
        label = str(line["id"])
        box = draw.textbbox((x, y), label, font=font)
        draw.rectangle((box[0] - 2, box[1] - 1, box[2] + 2, box[3] + 1), fill=(255, 255, 255))
        draw.text((x, y), label, fill=colour, font=font)
    return figure_png(img)


def k1_plot_svg(details: Mapping[str, Any]) -> bytes:
    """k1 of each line against its signed distance from the centre (cf. the paper's Figs. 9-14).

    Filled markers with 1-sigma error bars: the joint estimator; hollow
    markers: the paper's estimator; the band: the global model's k1 ± 1
    standard error (a line's expected k1 also depends on k2 and the centre,
    which the band does not show).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    matplotlib.rcParams["svg.hashsalt"] = "forensics"
    # Text as text and the markers as one embedded raster: drawn as paths, a
    # plot of a hundred lines held a thousand SVG nodes, which took the PDF
    # renderer 0.3 s; the axes, band and labels stay vector.
    matplotlib.rcParams["svg.fonttype"] = "none"
    lines = [ln for ln in details.get("lines", []) if ln.get("k1") is not None]
    fig, ax = plt.subplots(figsize=(4.3, 2.9), dpi=100)
    model = details.get("global_model")
    if model:
        ax.axhspan(model["k1"] - model["k1_stderr"], model["k1"] + model["k1_stderr"], color="0.85", zorder=0)
        ax.axhline(model["k1"], color="0.4", lw=1,
                   label=f"the photo's k1 = {model['k1']:.3f} ± {model['k1_stderr']:.3f} (band: one s.e.)")
    for cls, colour in COLOURS.items():
        sel = [ln for ln in lines if line_class(ln) == cls]
        if not sel:
            continue
        d = np.array([ln["distance"] for ln in sel])
        k = np.array([ln["k1"] for ln in sel])
        se = np.array([ln["k1_stderr"] if ln["k1_stderr"] is not None else 0.0 for ln in sel])
        ax.errorbar(d, k, yerr=se, fmt="o", ms=4, color=np.array(colour) / 255, capsize=2, label=f"{cls} (joint)",
                    rasterized=True)
        paper = [(ln["distance"], ln["k1_paper"]) for ln in sel if ln.get("k1_paper") is not None]
        if paper:
            pd_, pk = zip(*paper)
            ax.scatter(pd_, pk, s=18, facecolors="none", edgecolors=np.array(colour) / 255, rasterized=True)
    if lines:
        ks = np.array([ln["k1"] for ln in lines])
        lo, hi = np.percentile(ks, [2, 98])
        pad = max(0.05, 0.2 * (hi - lo))
        ax.set_ylim(lo - pad, hi + pad)
    ax.set_xlabel("signed distance from the image centre (normalised)", fontsize=8)
    ax.set_ylabel("k1 (hollow: paper's estimator)", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.axvline(0, color="0.7", lw=0.5)
    ax.legend(fontsize=6, loc="best")
    fig.tight_layout()
    out = io.BytesIO()
    fig.savefig(out, format="svg", metadata={"Date": None}, dpi=200)
    plt.close(fig)
    return out.getvalue()
