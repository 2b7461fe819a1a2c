"""``forensics validate``: measure the detectors' error rates on photos of known origin."""

from __future__ import annotations

from pathlib import Path

import click
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from ..defaults import DEFAULT_COUNT, DEFAULT_REAL_CORPUS, DEFAULT_SEED, DEFAULT_TIMEOUT_S

console = Console(stderr=True, highlight=False, emoji=False)


@click.command("validate")
@click.argument("suites", nargs=-1, required=True)
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Output folder: validation.json, validation.html, findings/, thumbnails/ of the authentic photos "
                   "convicted and, for the suites it builds (synthetic, lens-splices, innocent-processing, realistic), "
                   "cases/.")
@click.option("--detectors", help="Comma-separated detector names (default: all installed).")
@click.option("--workers", type=click.IntRange(min=1), default=None, help="Worker processes (default: number of cores).")
@click.option("--seed", type=int, default=DEFAULT_SEED, show_default=True,
              help="Seed of the synthetic and real-corpus (lens-splices, innocent-processing, realistic) suites.")
@click.option("--count", type=click.IntRange(min=1), default=DEFAULT_COUNT, show_default=True,
              help="Authentic and spliced photos per detector in the synthetic suite.")
@click.option("--corpus", type=click.Path(file_okay=False, path_type=Path), default=DEFAULT_REAL_CORPUS,
              show_default=True,
              help="Real corpus the lens-splices, innocent-processing and realistic suites are built from (only "
                   "read).")
@click.option("--timeout", type=click.FloatRange(min=0, min_open=True), default=DEFAULT_TIMEOUT_S, show_default=True,
              help="Time limit per detector and photo, seconds.")
@click.option("--fusion", default="bonferroni", show_default=True, help="Fusion policy for the verdict.")
@click.pass_context
def validate_command(ctx, *, suites, out_dir, detectors, workers, seed, count, corpus, timeout, fusion):
    """Run the detectors over SUITES and write their known error rates in one record.

    SUITES is `synthetic` (every detector's synthetic photos, generated from
    --seed; nothing is downloaded), `lens-splices` (the lens-distortion
    paper's three kinds of splice and controls, forged from the real
    authentic building photos of --corpus with --seed into OUT/cases/),
    `innocent-processing` (the same photos only processed as editors and
    platforms do, all authentic, made likewise), `realistic` (splices from
    another camera's photo, copy-moves and removals with object-like
    outlines, each beside a control saved the same way, made likewise) or
    one or more folders: a
    set (with a truth.csv, or with authentic/ and tampered/ subfolders and
    masks) or a parent folder whose descendant folders with a truth.csv are
    the sets (see the README). Every photo gets the condition `set`.
    Per detector and for the fused verdict: ROC AUC with a bootstrap 95%
    interval, TPR at FPR 1% and 5%, the operating point, per-condition and
    per-set figures, localisation (pixel F1, MCC, IoU; each detector's map
    and the report's Where map, overall and per set) where masks exist, how often
    each detector declined, and whether its p-values hold on the authentic
    photos (their empirical CDF and the photos it convicts).
    """
    from ..analysis import Options
    from . import (INNOCENT_PROCESSING, LENS_SPLICES, REALISTIC, RECORD_NAME, SYNTHETIC, SuiteError, default_workers,
                   innocent_processing_suite, lens_splices_suite, read_suite, realistic_suite, synthetic_suite,
                   validate)
    from .record import VERDICT

    host = ctx.find_root().command.host
    names = [d.strip() for d in detectors.split(",") if d.strip()] if detectors else None
    options = Options(detectors=names, timeout_s=timeout, fusion=fusion)
    try:
        options = options.resolve(host)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--detectors") from None
    unknown = sorted(set(names or ()) - set(host.detectors))
    if unknown:
        raise click.BadParameter(f"not installed: {', '.join(unknown)}", param_hint="--detectors")
    from_corpus = {LENS_SPLICES: lens_splices_suite, INNOCENT_PROCESSING: innocent_processing_suite,
                   REALISTIC: realistic_suite}
    synthetic = SYNTHETIC in suites
    built = synthetic or not from_corpus.keys().isdisjoint(suites)
    if built and len(suites) > 1:
        raise click.BadParameter(f"{', '.join((SYNTHETIC, *from_corpus))} are each measured on their own, not with "
                                 "other suites", param_hint="SUITES")
    try:
        if synthetic:
            with console.status(f"generating the synthetic suite (seed {seed}, {count} + {count} per detector)"):
                the_suite = synthetic_suite(
                    host, out_dir / "cases", seed, count,
                    on_problem=lambda p: console.print(f"forensics: warning: detector {p.detector} could not generate "
                                                       f"synthetic cases: {p.reason}", markup=False))
        elif built:
            with console.status(f"building the {suites[0]} suite from {corpus} (seed {seed})"):
                the_suite = from_corpus[suites[0]](corpus, out_dir / "cases", seed)
        else:
            the_suite = read_suite([Path(s) for s in suites])
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
                          seed=seed if built else None, count=count if synthetic else None)
    table = Table(title=f"{record.dataset.name}: {record.dataset.n_spliced} spliced, {record.dataset.n_authentic} authentic")
    table.add_column("method", no_wrap=True)
    for col in ("AUC (95% CI)", "TPR @ FPR 5%", "TPR / FPR at its rule", "declined",
                "authentic convicted"):
        table.add_column(col)
    checks = {c.name: c for c in record.null_checks}
    for m in record.methods:
        auc = "—" if m.auc is None else f"{m.auc:.3f}" + (f" ({m.auc_ci[0]:.3f}–{m.auc_ci[1]:.3f})" if m.auc_ci else "")
        t5 = m.tpr_at_fpr["0.05"]
        op = m.operating_point
        declined = (m.declined_spliced.k + m.declined_authentic.k) / max(1, m.n_spliced + m.n_authentic)
        convicted = checks[m.name].convicted if m.name in checks else None
        table.add_row("fused verdict" if m.name == VERDICT else m.name, auc, "—" if t5 is None else f"{t5:.2f}",
                      f"{op.tpr.value or 0:.2f} / {op.fpr.value or 0:.2f}", f"{declined:.0%}",
                      "—" if convicted is None or not convicted.n else f"{convicted.k}/{convicted.n}")
    Console(highlight=False, emoji=False).print(table)
    from .page import PAGE_NAME

    click.echo(f"{out_dir / RECORD_NAME}\n{out_dir / PAGE_NAME}")
    if failures:
        console.print(f"forensics: {failures} photo(s) could not be analysed; see {RECORD_NAME}", markup=False)
        ctx.exit(1)
