"""``forensics validate``: measure the detectors' error rates on photos of known origin."""

from __future__ import annotations

from pathlib import Path

import click
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from ..analysis import DEFAULT_TIMEOUT_S, Options, resolve_params
from ..plugins import PluginHost
from . import (
    DEFAULT_COUNT,
    DEFAULT_SEED,
    RECORD_NAME,
    SYNTHETIC,
    SuiteError,
    default_workers,
    folder_suite,
    synthetic_suite,
    validate,
)
from .page import PAGE_NAME
from .record import VERDICT

console = Console(stderr=True, highlight=False)


@click.command("validate")
@click.argument("suite")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Output folder: validation.json, validation.html, findings/ and, for the synthetic suite, cases/.")
@click.option("--detectors", help="Comma-separated detector names (default: all installed).")
@click.option("--workers", type=click.IntRange(min=1), default=None, help="Worker processes (default: number of cores).")
@click.option("--seed", type=int, default=DEFAULT_SEED, show_default=True, help="Seed of the synthetic suite.")
@click.option("--count", type=click.IntRange(min=1), default=DEFAULT_COUNT, show_default=True,
              help="Authentic and spliced photos per plugin in the synthetic suite.")
@click.option("--timeout", type=click.FloatRange(min=0, min_open=True), default=DEFAULT_TIMEOUT_S, show_default=True,
              help="Time limit per detector and photo, seconds.")
@click.option("--fusion", default="bonferroni", show_default=True, help="Fusion policy for the verdict.")
@click.pass_context
def validate_command(ctx, suite, out_dir, detectors, workers, seed, count, timeout, fusion):
    """Run the detectors over SUITE and write its known error rates.

    SUITE is `synthetic` (every plugin's synthetic photos, generated from
    --seed; nothing is downloaded) or a folder with a truth.csv, or with
    authentic/ and tampered/ subfolders and masks (see the README).
    Per detector and for the fused verdict: ROC AUC with a bootstrap 95%
    interval, TPR at FPR 1% and 5%, the operating point, per-condition
    figures, localisation MCC and IoU where masks exist, and how often each
    detector declined.
    """
    host: PluginHost = ctx.find_root().command.host
    names = [d.strip() for d in detectors.split(",") if d.strip()] if detectors else None
    options = Options(detectors=names, timeout_s=timeout, fusion=fusion)
    try:
        resolve_params(host, options)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--detectors") from None
    unknown = sorted(set(names or ()) - set(host.detectors))
    if unknown:
        raise click.BadParameter(f"not installed: {', '.join(unknown)}", param_hint="--detectors")
    try:
        if suite == SYNTHETIC:
            with console.status(f"generating the synthetic suite (seed {seed}, {count} + {count} per plugin)"):
                the_suite = synthetic_suite(
                    host, out_dir / "cases", seed, count,
                    on_problem=lambda p: console.print(f"forensics: warning: plugin {p.plugin} could not generate "
                                                       f"synthetic cases: {p.reason}", markup=False))
        else:
            the_suite = folder_suite(Path(suite))
    except SuiteError as exc:
        console.print(f"forensics: error: {exc}", markup=False, soft_wrap=True)
        ctx.exit(1)
    failures = 0
    progress = Progress(TextColumn("validating"), BarColumn(), MofNCompleteColumn(), TextColumn("failed {task.fields[failed]}"),
                        TimeElapsedColumn(), TimeRemainingColumn(), console=console, transient=True)
    with progress:
        task = progress.add_task("validating", total=len(the_suite.cases), failed=0)

        def done(result):
            nonlocal failures
            failures += result.error is not None
            progress.update(task, advance=1, failed=failures)

        record = validate(the_suite, out_dir, host, options, workers or default_workers(), done,
                          seed=seed if suite == SYNTHETIC else None, count=count if suite == SYNTHETIC else None)
    table = Table(title=f"{record.dataset.name}: {record.dataset.n_spliced} spliced, {record.dataset.n_authentic} authentic")
    for col in ("method", "AUC (95% CI)", "TPR @ FPR 5%", "TPR / FPR at its rule", "declined"):
        table.add_column(col)
    for m in record.methods:
        auc = "—" if m.auc is None else f"{m.auc:.3f}" + (f" ({m.auc_ci[0]:.3f}–{m.auc_ci[1]:.3f})" if m.auc_ci else "")
        t5 = m.tpr_at_fpr["0.05"]
        op = m.operating_point
        declined = (m.declined_spliced.k + m.declined_authentic.k) / max(1, m.n_spliced + m.n_authentic)
        table.add_row("fused verdict" if m.name == VERDICT else m.name, auc, "—" if t5 is None else f"{t5:.2f}",
                      f"{op.tpr.value or 0:.2f} / {op.fpr.value or 0:.2f}", f"{declined:.0%}")
    Console(highlight=False).print(table)
    click.echo(f"{out_dir / RECORD_NAME}\n{out_dir / PAGE_NAME}")
    if failures:
        console.print(f"forensics: {failures} photo(s) could not be analysed; see {RECORD_NAME}", markup=False)
        ctx.exit(1)
