"""The HTML page of a validation run: ROC curves and tables, self-contained."""

from __future__ import annotations

import base64
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
from jinja2 import Environment, FunctionLoader, StrictUndefined  # noqa: E402

from ..output import write_atomic  # noqa: E402
from ..report.render import template_text  # noqa: E402
from .metrics import BOOTSTRAP_SAMPLES, Rate  # noqa: E402
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
    fig.tight_layout()
    buf = io.BytesIO()
    # A fixed hash salt and no date keep the SVG identical from run to run.
    with plt.rc_context({"svg.hashsalt": "forensics"}):
        fig.savefig(buf, format="svg", metadata={"Date": None})
    plt.close(fig)
    return buf.getvalue()


def _pct(r: Rate) -> str:
    if r.value is None:
        return "—"
    lo, hi = r.ci
    return f"{100 * r.value:.1f}% ({r.k}/{r.n}; 95% CI {100 * lo:.1f}–{100 * hi:.1f}%)"


def _num(value: float | None, fmt: str = ".3f") -> str:
    return "—" if value is None else format(value, fmt)


def render_page(record: ValidationRecord) -> str:
    """The page's HTML text (autoescaped; figures inline as data: URLs)."""
    env = Environment(loader=FunctionLoader(template_text), autoescape=True, undefined=StrictUndefined,
                      trim_blocks=True, lstrip_blocks=True)
    env.filters.update(pct=_pct, num=_num)
    roc = base64.b64encode(roc_svg(record.methods)).decode("ascii")
    return env.get_template("validation.html.j2").render(record=record, roc=f"data:image/svg+xml;base64,{roc}",
                                                         verdict_name=VERDICT, css=template_text("report.css"),
                                                         bootstrap_samples=BOOTSTRAP_SAMPLES)


def write_page(record: ValidationRecord, folder: Path) -> Path:
    return write_atomic(folder / PAGE_NAME, render_page(record).encode("utf-8"))
