"""The HTML page of a validation run: ROC curves, null checks on authentic photos and tables, self-contained."""

from __future__ import annotations

import base64
import io
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402
from jinja2 import Environment, FunctionLoader, StrictUndefined  # noqa: E402

from ..atomic import write_atomic  # noqa: E402
from ..report.render import template_text  # noqa: E402
from .metrics import BOOTSTRAP_SAMPLES, Rate  # noqa: E402
from .null_check import NULL_LEVELS, authentic_p_values, convictions, ecdf, pointwise_limit  # noqa: E402
from .record import VERDICT, MethodMetrics, ValidationRecord  # noqa: E402

PAGE_NAME = "validation.html"


def roc_svg(methods: list[MethodMetrics]) -> bytes:
    """ROC curves of ``methods`` on one plot, with the chance diagonal, as SVG bytes."""
    fig, ax = plt.subplots(figsize=(5.2, 4.6))
    ax.plot([0, 1], [0, 1], color="0.75", lw=0.8, ls="--", label="chance")
    for m in methods:
        if not m.roc:
            continue
        fpr, tpr = zip(*m.roc)
        label = f"{m.name} (AUC {m.auc:.3f})" if m.auc is not None else m.name
        ax.step(fpr, tpr, where="post", lw=2.2 if m.name == VERDICT else 1.2, label=label,
                color="black" if m.name == VERDICT else None)
    for x in (0.01, 0.05):
        ax.axvline(x, color="0.85", lw=0.6)
    ax.set_xlabel("false-positive rate (authentic photos flagged)")
    ax.set_ylabel("true-positive rate (spliced photos flagged)")
    ax.set_xlim(-0.01, 1.01)
    ax.set_ylim(-0.01, 1.01)
    ax.legend(loc="lower right", fontsize=7, frameon=False)
    return _svg(fig)


def _svg(fig) -> bytes:
    fig.tight_layout()
    buf = io.BytesIO()
    # A fixed hash salt and no date keep the SVG identical from run to run.
    with plt.rc_context({"svg.hashsalt": "forensics"}):
        fig.savefig(buf, format="svg", metadata={"Date": None})
    plt.close(fig)
    return buf.getvalue()


def ecdf_svg(p_values: np.ndarray, title: str, level: float | None) -> bytes:
    """Empirical CDF of authentic photos' p-values against the diagonal, on log axes, as SVG bytes.

    A valid test lies on or below the diagonal; the dashed line is the
    pointwise 95 % upper limit of the curve of as many uniform p-values.
    p = 0 is drawn at 1e-300. The share axis stops at half of 1/n, the
    smallest share n photos can show.
    """
    p = np.maximum(np.asarray(p_values, dtype=float), 1e-300)
    x, y = ecdf(p)
    low = min(x[0], 0.5 / len(p))
    grid = np.geomspace(low, 1.0, 240)
    limit = pointwise_limit(grid, len(p))
    fig, ax = plt.subplots(figsize=(3.6, 3.3))
    ax.plot(grid, grid, color="0.6", lw=0.8)
    ax.plot(grid, np.where(limit > 0, limit, np.nan), color="0.6", lw=0.8, ls="--")
    ax.step(np.r_[x, 1.0], np.r_[y, 1.0], where="post", color="black", lw=1.4)
    if level is not None:
        ax.axvline(level, color="tab:red", lw=0.6)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(low, 1.0)
    ax.set_ylim(0.5 / len(p), 1.05)
    ax.set_xlabel("p-value t")
    ax.set_ylabel("share of authentic photos with p ≤ t")
    ax.set_title(title, fontsize=9)
    return _svg(fig)


def tippett_svg(llrs: Mapping[str, Mapping[str, list[float]]]) -> bytes:
    """Tippett plots: per method, the share of Hp (solid) and Hd (dashed) photos whose log10 LR exceeds x."""
    names = list(llrs)
    ncols = min(3, len(names))
    nrows = -(-len(names) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(2.3 * ncols, 2.2 * nrows), sharey=True, squeeze=False)
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    for ax, name in zip(axes.ravel(), names):
        for side, style, colour in (("hp", "-", "tab:red"), ("hd", "--", "tab:blue")):
            v = np.sort(np.asarray(llrs[name][side], dtype=float))
            if v.size:
                x = np.concatenate([[v[0] - 0.5], v, [v[-1] + 0.5]])
                share = np.concatenate([[1.0], 1.0 - np.arange(1, v.size + 1) / v.size, [0.0]])
                ax.step(x, share, where="post", ls=style, color=colour, label="Hp" if side == "hp" else "Hd")
        ax.axvline(0, color="0.7", lw=0.6)
        ax.set_title(_label(name), fontsize=8)
        ax.set_xlabel("log10 LR", fontsize=7)
        ax.tick_params(labelsize=6)
    for row in axes:
        row[0].set_ylabel("share above x", fontsize=7)
    axes[0][0].legend(fontsize=6, frameon=False)
    return _svg(fig)


def ece_svg(llrs: Mapping[str, list[float]], title: str) -> bytes:
    """Empirical cross-entropy against the prior log10 odds, with the neutral reference (LR 1 everywhere).

    ``ECE = P(Hp) mean_Hp log2(1 + 1 / (LR O)) + P(Hd) mean_Hd log2(1 + LR O)``
    at prior odds ``O`` (Ramos et al., 2013); below the neutral curve, the
    LRs help a decision at that prior.
    """
    prior = np.linspace(-2.5, 2.5, 101)
    odds = 10.0 ** prior
    hp = 10.0 ** np.asarray(llrs["hp"], dtype=float)
    hd = 10.0 ** np.asarray(llrs["hd"], dtype=float)
    p_hp = odds / (1.0 + odds)
    ece = (p_hp * np.log2(1.0 + 1.0 / (hp[None, :] * odds[:, None])).mean(axis=1)
           + (1.0 - p_hp) * np.log2(1.0 + hd[None, :] * odds[:, None]).mean(axis=1))
    neutral = p_hp * np.log2(1.0 + 1.0 / odds) + (1.0 - p_hp) * np.log2(1.0 + odds)
    fig, ax = plt.subplots(figsize=(4.2, 2.8))
    ax.plot(prior, neutral, color="0.6", ls="--", label="neutral (LR 1)")
    ax.plot(prior, ece, color="black", label="these LRs")
    ax.set_xlabel("prior log10 odds of Hp", fontsize=8)
    ax.set_ylabel("empirical cross-entropy (bits)", fontsize=8)
    ax.set_title(title, fontsize=8)
    ax.legend(fontsize=7, frameon=False)
    return _svg(fig)


def _data_url(data: bytes, mime: str) -> str:
    return f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"


def _pct(r: Rate) -> str:
    if r.value is None:
        return "—"
    lo, hi = r.ci
    return f"{100 * r.value:.1f}% ({r.k}/{r.n}; 95% CI {100 * lo:.1f}–{100 * hi:.1f}%)"


def _num(value: float | None, fmt: str = ".3f") -> str:
    return "—" if value is None else format(value, fmt)


def _p_text(value: float | None) -> str:
    return "—" if value is None else f"{value:.3g}"


def _label(name: str) -> str:
    return "fused verdict" if name == VERDICT else name


def render_page(record: ValidationRecord, thumbnails: Mapping[tuple[str, str], Path] | None = None) -> str:
    """The page's HTML text (autoescaped; figures and ``thumbnails``, keyed by (photo, detector), inline as data: URLs)."""
    env = Environment(loader=FunctionLoader(template_text), autoescape=True, undefined=StrictUndefined,
                      trim_blocks=True, lstrip_blocks=True)
    env.filters.update(pct=_pct, num=_num, p=_p_text, label=_label)
    level = record.fusion.get("alpha")
    ecdfs = {}
    for check in record.null_checks:
        p = authentic_p_values(record.cases, check.name)
        if len(p):
            ecdfs[check.name] = _data_url(ecdf_svg(p, f"{_label(check.name)} ({len(p)} authentic photos)", level),
                                          "image/svg+xml")
    thumbs = {key: _data_url(path.read_bytes(), "image/jpeg") for key, path in (thumbnails or {}).items()
              if path.is_file()}
    lr = record.likelihood_ratios or {}
    lr_figures = {}
    if lr.get("llrs"):
        lr_figures["tippett"] = _data_url(tippett_svg(lr["llrs"]), "image/svg+xml")
        lr_figures["ece"] = _data_url(ece_svg(lr["llrs"][VERDICT], "fused LR, cross-validated"), "image/svg+xml")
    return env.get_template("validation.html.j2").render(
        record=record, roc=_data_url(roc_svg(record.methods), "image/svg+xml"), verdict_name=VERDICT,
        css=template_text("report.css"), bootstrap_samples=BOOTSTRAP_SAMPLES, ecdfs=ecdfs,
        levels=[f"{t:g}" for t in NULL_LEVELS], convictions=convictions(record.cases, record.null_checks),
        thumbnails=thumbs, lr=lr, lr_figures=lr_figures, localisation=_localisation_rows(record))


def _localisation_rows(record: ValidationRecord) -> list[tuple[str, str, Any]]:
    """(method, condition, Localisation) for every method that localises: over all photos, then per condition."""
    rows = []
    for m in record.methods:
        if m.localisation is None:
            continue
        rows.append((m.name, "all", m.localisation))
        rows += [(m.name, f"{c.key} {c.value}", c.localisation) for c in m.by_condition if c.localisation is not None]
    return rows


def write_page(record: ValidationRecord, folder: Path,
               thumbnails: Mapping[tuple[str, str], Path] | None = None) -> Path:
    return write_atomic(folder / PAGE_NAME, render_page(record, thumbnails).encode("utf-8"))
