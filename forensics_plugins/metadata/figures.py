"""Figures of the metadata finding: the thumbnail beside the image, and the lens curves.

Metadata has no map; what the examiner needs to see is the embedded
thumbnail next to the stored picture (and where they differ), and the
distortion lensfun predicts next to the one the lens detector measured.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from typing import Any

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from forensics_core.report import figure_png

from .conversion import inverse
from .thumbnail import Comparison, to_8bit

PANEL_HEIGHT = 300
_GAP = 12
_CAPTION_PX = 22


def _panel_width(size: tuple[int, int]) -> int:
    return max(1, round(size[0] * PANEL_HEIGHT / size[1]))


def _difference_image(cmp: Comparison, threshold: float, size: tuple[int, int]) -> Image.Image:
    """The residual in the thumbnail's frame: grey below ``threshold``, red above, darker outside the picture area."""
    out = np.full((size[1], size[0], 3), 40, dtype=np.uint8)
    x0, y0, x1, y1 = cmp.box
    d = cmp.difference
    grey = np.clip(d / threshold * 160, 0, 160).astype(np.uint8)
    rgb = np.stack([grey, grey, grey], axis=-1)
    rgb[d > threshold] = (230, 40, 40)
    out[y0:y1, x0:x1] = rgb
    return Image.fromarray(out)


def thumbnail_png(pixels: np.ndarray, thumb: Image.Image, cmp: Comparison | None, threshold: float) -> bytes:
    """The stored image (reduced), the embedded thumbnail and, when compared, their difference.

    Parameters
    ----------
    pixels : ndarray, shape (H, W) or (H, W, C)
        The evidence's stored grid (orientation not applied).
    thumb : PIL.Image.Image
        The decoded thumbnail (orientation not applied).
    cmp : Comparison or None
        From :func:`.thumbnail.compare`; its picture area and the largest
        differing region are outlined.
    threshold : float
        The change threshold, luma on [0, 1].

    Returns
    -------
    bytes
        PNG, panels ``PANEL_HEIGHT`` pixels high.
    """
    img = Image.fromarray(to_8bit(pixels))
    # Reduce before anything else, so the cost does not grow with the photo;
    # a photo smaller than the panel is enlarged so the panels line up.
    img.thumbnail((4 * PANEL_HEIGHT, PANEL_HEIGHT), Image.Resampling.LANCZOS, reducing_gap=2.0)
    img = img.convert("RGB").resize((_panel_width(img.size), PANEL_HEIGHT), Image.Resampling.LANCZOS)
    t_w = _panel_width(thumb.size)
    t_big = thumb.convert("RGB").resize((t_w, PANEL_HEIGHT), Image.Resampling.NEAREST)
    factor = PANEL_HEIGHT / thumb.size[1]
    panels = [(img, "stored image (reduced)"), (t_big, "embedded thumbnail")]
    if cmp is not None and cmp.difference is not None:
        diff = _difference_image(cmp, threshold, thumb.size).resize((t_w, PANEL_HEIGHT), Image.Resampling.NEAREST)
        panels.append((diff, f"difference (red: > {threshold:g})"))
    width = sum(p.size[0] for p, _ in panels) + _GAP * (len(panels) - 1)
    canvas = Image.new("RGB", (width, PANEL_HEIGHT + _CAPTION_PX), (255, 255, 255))
    font = ImageFont.load_default(size=16)
    draw = ImageDraw.Draw(canvas)
    x = 0
    for k, (panel, label) in enumerate(panels):
        canvas.paste(panel, (x, _CAPTION_PX))
        draw.text((x + 2, 2), label, fill=(30, 30, 30), font=font)
        if k > 0 and cmp is not None:
            for box, colour in ((cmp.box, (40, 120, 230)), (cmp.changed_box, (245, 150, 20))):
                if box is not None:
                    x0, y0, x1, y1 = (v * factor for v in box)
                    draw.rectangle((x + x0, _CAPTION_PX + y0, x + x1 - 1, _CAPTION_PX + y1 - 1), outline=colour,
                                   width=2)
        x += panel.size[0] + _GAP
    return figure_png(canvas)


def lens_plot_svg(lens: Mapping[str, Any]) -> bytes:
    """Radial distortion against radius: lensfun's model, its two-term fit, and the measurement.

    The curves show ``r_u / (m r_d) - 1``, the relative radial displacement
    in the project's convention (positive: barrel), over the image's radii
    (project units, corner at ``r_max``). The measured curve is
    ``k1 r^2 + k2 r^4`` with a band of ``± 1.96 se(k1) r^2`` (k2's
    uncertainty and its covariance with k1 are not drawn).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    matplotlib.rcParams["svg.hashsalt"] = "forensics"
    r = np.linspace(0.01, lens["r_max"], 200)
    fig, ax = plt.subplots(figsize=(4.3, 2.9), dpi=100)
    exact = inverse(lens["model"], tuple(lens["terms"]), r * lens["scale"]) / lens["scale"]
    ax.plot(r, exact / (lens["magnification"] * r) - 1, color="0.2", lw=1.2,
            label=f"lensfun {lens['model']} at {lens['focal_mm']:g} mm")
    ax.plot(r, lens["k1_predicted"] * r**2 + lens["k2_predicted"] * r**4, color="0.2", lw=1, ls="--",
            label=f"two-term fit: k1 = {lens['k1_predicted']:+.4f}, k2 = {lens['k2_predicted']:+.4f}")
    if lens.get("k1_measured") is not None:
        k1, se, k2 = lens["k1_measured"], lens["k1_measured_stderr"], lens.get("k2_measured") or 0.0
        curve = k1 * r**2 + k2 * r**4
        ax.fill_between(r, curve - 1.96 * se * r**2, curve + 1.96 * se * r**2, color=(0.12, 0.67, 0.24, 0.25), lw=0)
        ax.plot(r, curve, color=(0.12, 0.67, 0.24), lw=1.4,
                label=f"measured: k1 = {k1:+.4f} ± {se:.4f}, k2 = {k2:+.4f}")
    ax.axhline(0, color="0.7", lw=0.5)
    ax.axvline(1, color="0.8", lw=0.5, ls=":")
    ax.set_xlabel("radius (half the longer side = 1; dotted: middle of the long edge)", fontsize=7)
    ax.set_ylabel("relative radial displacement", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=6, loc="best")
    fig.tight_layout()
    out = io.BytesIO()
    fig.savefig(out, format="svg", metadata={"Date": None})
    plt.close(fig)
    return out.getvalue()
