"""Run a batch: find and hash the photos, plan, hand the work to workers, record the summary and the index."""

from __future__ import annotations

import os
import time
from collections import Counter
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.progress import (BarColumn, MofNCompleteColumn, Progress, ProgressColumn, TextColumn, TimeElapsedColumn,
                           TimeRemainingColumn)
from rich.table import Table
from rich.text import Text

from .. import stopping
from ..plugins import PluginHost
from ..signing import ExaminerKey
from ..text import decoded, visible
from .cluster import ClusterError, DaskPool
from .index import BatchPhoto, write_index
from .inputs import discover, hash_all
from .local import Finished, LocalPool
from .plan import INDEX_HTML, Plan, make_plan
from .resume import Expected, LockHeld, OutputLock, expected_parameters, link_folder, remove_temp_files
from .summary import Row, counts, detector_names, fill_from_findings, previous_times, write_summary
from .work import Settings, preload

FailLine = Callable[[str, str], None]
_REFRESH_S = 0.2


class BatchError(Exception):
    """The batch cannot start (output folder, lock, scheduler); the message is one line."""


@dataclass(frozen=True)
class BatchRequest:
    """What the user asked for.

    Attributes
    ----------
    inputs : list of Path
        Files and folders.
    out_dir : Path
    settings : Settings
        How each photo is analysed and reported.
    recursive : bool
        Folders give all their descendants, not only their children.
    workers : int or None
        Local worker processes (default: the usable CPU cores).
    scheduler : str or None
        Address of a Dask scheduler; the cluster's workers are used instead.
    force : bool
        Redo photos whose outputs are finished.
    """

    inputs: list[Path]
    out_dir: Path
    settings: Settings
    recursive: bool = False
    workers: int | None = None
    scheduler: str | None = None
    force: bool = False


@dataclass
class BatchResult:
    rows: list[Row]
    summary_json: Path
    summary_csv: Path
    elapsed_s: float
    pool: str
    peaks_mb: dict[str, float | None] = field(default_factory=dict)
    index_html: Path | None = None

    @property
    def failed(self) -> int:
        return sum(r.outcome in ("failed", "pending") for r in self.rows)


def default_workers() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


class _RateColumn(ProgressColumn):
    """Photos per minute over rich's recent-progress window."""

    def render(self, task) -> Text:
        speed = task.speed
        return Text(f"{speed * 60:.1f}/min" if speed else "-/min", style="progress.data.speed")


def _progress(console: Console) -> Progress:
    # No auto-refresh thread: local workers are forked from this process, and
    # a thread caught mid-write would leave its locks held in every child.
    return Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), _RateColumn(),
                    TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
                    TextColumn("{task.fields[failed]} failed"), console=console, auto_refresh=False, transient=True)


class _Batch:
    """The rows and the bookkeeping of one run."""

    def __init__(self, plan: Plan, fail_line: FailLine):
        self.plan, self.fail_line = plan, fail_line
        self.rows: dict[Path, Row] = {p.path: Row(decoded(str(p.path)), p.sha256) for p in plan.photos}
        self.peaks: dict[str, float | None] = {"worker_mb": None, "detector_child_mb": None}
        self.n_failed = 0

    def failed(self, path: Path, reason: str, attempts: int | None = None) -> None:
        row = self.rows[path]
        row.outcome, row.error, row.attempts = "failed", reason, attempts
        self.n_failed += 1
        self.fail_line(str(path), reason)

    def settle_known(self, times: dict[tuple[str, str], float]) -> int:
        """Fill the rows that need no work: unreadable inputs, finished photos and their duplicates."""
        done = 0
        for photo in self.plan.photos:
            if photo.error is not None:
                self.failed(photo.path, photo.error)
                done += 1
        for group in self.plan.groups.values():
            if group.needs_run:
                continue
            primary = group.primary.paths[0]
            self._from_folder(primary, self.plan.folder(group.primary), "resumed")
            row = self.rows[primary]
            row.time_s = times.get((row.photo, row.sha256))
            done += 1 + self.settle_duplicates(group.sha256)
        return done

    def _from_folder(self, path: Path, folder: Path, outcome: str) -> None:
        row = self.rows[path]
        row.output = decoded(str(folder))
        if fill_from_findings(row, folder):
            row.outcome = outcome
        else:
            self.failed(path, f"cannot read {folder / 'findings.json'}")

    def settle_duplicates(self, sha256: str) -> int:
        """Link and fill the duplicates of a finished primary; return how many rows were settled."""
        group = self.plan.groups[sha256]
        primary = group.primary.paths[0]
        settled = 0
        for entry in [group.primary, *group.others]:
            if entry is not group.primary and not entry.complete:
                try:
                    link_folder(self.plan.out_dir, entry.name, group.primary.name)
                except OSError as exc:
                    for path in entry.paths:
                        self.failed(path, f"cannot link to the outputs of {primary}: {exc.strerror or exc}")
                    settled += len(entry.paths)
                    continue
            for path in entry.paths:
                if path == primary:
                    continue
                self.rows[path].duplicate_of = decoded(str(primary))
                self._from_folder(path, self.plan.folder(entry), "duplicate")
                settled += 1
        return settled

    def finish(self, finished: Finished) -> int:
        """Record a photo the workers are done with, and its duplicates; return how many rows were settled."""
        job, outcome = finished.job, finished.outcome
        primary = Path(job.path)
        group = self.plan.groups[job.sha256]
        for name, value in (("worker_mb", outcome.worker_peak_mb), ("detector_child_mb", outcome.child_peak_mb)):
            if value is not None:
                self.peaks[name] = max(value, self.peaks[name] or 0.0)
        row = self.rows[primary]
        row.time_s, row.attempts = outcome.seconds or None, finished.attempts
        if outcome.error is not None:
            self.failed(primary, outcome.error, finished.attempts)
            for entry in [group.primary, *group.others]:
                for path in entry.paths:
                    if path != primary:
                        self.rows[path].duplicate_of = decoded(str(primary))
                        self.failed(path, f"same bytes as {decoded(str(primary))}, which failed")
            return sum(len(e.paths) for e in [group.primary, *group.others])
        for url in outcome.refused_urls:
            self.fail_line(job.folder, f"the PDF renderer was refused {url[:100]!r} (only data: URLs are allowed)")
        row.outcome, row.output, row.verdict = "analysed", decoded(job.folder), outcome.verdict
        row.log10_lr = outcome.log10_lr
        row.detectors = {name: {"status": status, "score": score} for name, status, score in outcome.detectors}
        return 1 + self.settle_duplicates(job.sha256)


def _prepare_folders(plan: Plan) -> None:
    """Remove what a killed run left: temporary files, and links where a primary's own folder belongs."""
    remove_temp_files(plan.out_dir)
    for group in plan.groups.values():
        for entry in [group.primary, *group.others]:
            folder = plan.folder(entry)
            if folder.is_dir() and not folder.is_symlink():
                remove_temp_files(folder)
        if group.needs_run and plan.folder(group.primary).is_symlink():
            plan.folder(group.primary).unlink()


def run_batch(request: BatchRequest, host: PluginHost, key: ExaminerKey | None, console: Console,
              fail_line: FailLine) -> BatchResult:
    """Examine every photo of ``request``; see :mod:`forensics_core.batch`.

    Parameters
    ----------
    request : BatchRequest
    host : PluginHost
        The loaded plugins (local workers inherit them).
    key : ExaminerKey or None
        The signing key, needed when reports are asked for.
    console : Console
        Where the progress bar is drawn (stderr).
    fail_line : callable
        ``fail_line(subject, reason)`` prints one failure line.

    Raises
    ------
    BatchError
        When the output folder cannot be made or is locked by another batch,
        or the scheduler cannot be reached.
    KeyboardInterrupt
        After the summary of what was done has been written.
    """
    started = time.perf_counter()
    out_dir = request.out_dir
    options = request.settings.options.resolve(host)
    settings = replace(request.settings, options=options)
    expected = Expected(settings.report_formats,
                        expected_parameters(list(options.detectors), options.detector_params, options.fusion,
                                            options.case_id, options.examiner, options.reference),
                        settings.report_options.exhibit_id)
    with ExitStack() as stack:
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
            stack.enter_context(OutputLock(out_dir))
        except LockHeld as exc:
            raise BatchError(str(exc)) from None
        except OSError as exc:
            raise BatchError(f"cannot use the output folder {out_dir}: {exc.strerror or exc}") from None
        progress = stack.enter_context(_progress(console))
        found = discover(request.inputs, out_dir, request.recursive)
        hashing = progress.add_task("hashing", total=len(found), failed=0)
        photos = []
        shown = 0.0
        for photo in hash_all(found):
            photos.append(photo)
            progress.advance(hashing)
            if time.monotonic() - shown > _REFRESH_S:
                progress.refresh()
                shown = time.monotonic()
        progress.remove_task(hashing)
        plan = make_plan(photos, out_dir, expected, request.force)
        _prepare_folders(plan)
        batch = _Batch(plan, fail_line)
        settled = batch.settle_known(previous_times(out_dir))
        task = progress.add_task("analysing", total=len(plan.photos), completed=settled, failed=batch.n_failed)
        progress.refresh()
        pool_name = "no work"
        try:
            jobs = plan.jobs()
            if jobs:
                if request.scheduler is None:
                    preload(host, key)
                    pool = LocalPool(request.workers or default_workers(), settings)
                else:
                    pool = DaskPool(request.scheduler, settings)
                with pool:
                    pool_name = pool.describe()
                    for finished in pool.run(jobs, on_idle=progress.refresh):
                        progress.update(task, advance=batch.finish(finished), failed=batch.n_failed)
                        progress.refresh()
                        stopping.check()
        except ClusterError as exc:
            raise BatchError(str(exc)) from None
        finally:
            rows = [batch.rows[p.path] for p in plan.photos]
            elapsed = round(time.perf_counter() - started, 3)
            run = _run_record(request, settings, pool_name, elapsed, batch.peaks)
            json_path, csv_path = write_summary(out_dir, rows, detector_names(rows, list(options.detectors)), run)
            index = _write_index(plan, batch)
    return BatchResult(rows, json_path, csv_path, elapsed, pool_name, batch.peaks, index)


def _write_index(plan: Plan, batch: _Batch) -> Path | None:
    """Write ``index.html`` for every photo of the plan; None (and a failure line) when it cannot be written.

    The summary is the batch's record; a page that cannot be written is reported, not a reason to lose the run.
    """
    photos = [BatchPhoto(p.path, batch.rows[p.path],
                         plan.folder(plan.entry_of[p.path]) if p.path in plan.entry_of else None)
              for p in plan.photos]
    try:
        return write_index(plan.out_dir, photos)
    except OSError as exc:
        batch.fail_line(str(plan.out_dir / INDEX_HTML), f"cannot write the batch index: {exc.strerror or exc}")
        return None


def _run_record(request: BatchRequest, settings: Settings, pool: str, elapsed: float,
                peaks: dict[str, float | None]) -> dict[str, Any]:
    return {
        "inputs": [decoded(str(p)) for p in request.inputs],
        "out_dir": decoded(str(request.out_dir)),
        "recursive": request.recursive,
        "force": request.force,
        "workers": pool,
        "scheduler": request.scheduler,
        "detectors": list(settings.options.detectors or []),
        "report_formats": list(settings.report_formats),
        "elapsed_s": elapsed,
        "peak_worker_mb": peaks.get("worker_mb"),
        "peak_detector_child_mb": peaks.get("detector_child_mb"),
    }


def print_summary(result: BatchResult, console: Console) -> None:
    """The end-of-run tables: photos by outcome and verdict, and each detector's statuses."""
    tally = counts(result.rows)
    table = Table(title="batch summary", show_header=True)
    table.add_column("photos")
    table.add_column("count", justify="right")
    for outcome in ("analysed", "resumed", "duplicate", "failed", "pending"):
        if tally[outcome] or outcome in ("analysed", "failed"):
            table.add_row(outcome, str(tally[outcome]))
    table.add_row("total", str(tally["photos"]), end_section=True)
    for verdict, n in tally["verdicts"].items():
        table.add_row(f"verdict {verdict}", str(n))
    console.print(table)
    statuses = ("ok", "inconclusive", "skipped", "error")
    per_detector: dict[str, Counter] = {}
    for row in result.rows:
        for name, entry in row.detectors.items():
            per_detector.setdefault(name, Counter())[entry.get("status")] += 1
    if per_detector:
        det = Table(title="detectors")
        det.add_column("detector")
        for status in statuses:
            det.add_column(status, justify="right")
        for name, tally_d in per_detector.items():
            det.add_row(escape(name), *(str(tally_d.get(s, 0)) for s in statuses))
        console.print(det)
    analysed = tally["analysed"]
    rate = f", {analysed / result.elapsed_s * 60:.1f} photos/min" if analysed and result.elapsed_s > 0 else ""
    console.print(f"{analysed} analysed in {result.elapsed_s:.1f} s{rate} ({result.pool})", markup=False,
                  highlight=False)
    console.print(f"summary: {visible(str(result.summary_csv))}, {visible(str(result.summary_json))}", markup=False,
                  highlight=False)
    if result.index_html is not None:
        console.print(f"index: {visible(str(result.index_html))}", markup=False, highlight=False)
