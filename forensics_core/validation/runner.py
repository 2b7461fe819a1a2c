"""Analyse every photo of a suite, in worker processes, and keep what the metrics need."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from ..analysis import Options, analyze_evidence
from ..evidence import EvidenceError, load_evidence
from ..findings import Findings, Status, VerdictLabel
from ..fusion import finding_p
from ..atomic import write_atomic
from ..plugins import PluginHost, localise_map, one_line
from ..report.wording import found_something
from .cases import Case, load_mask
from .metrics import f1, iou, mcc


@dataclass
class DetectorOutcome:
    """One detector on one photo: its numbers, and its localisation scores where a true mask exists."""

    status: Status
    p_value: float | None
    score: float | None
    error: str | None
    elapsed_s: float
    mcc: float | None = None
    iou: float | None = None
    f1: float | None = None


@dataclass
class CaseResult:
    """Everything the metrics use about one photo; ``error`` when it could not be taken in."""

    name: str
    spliced: bool
    conditions: dict[str, str]
    sha256: str | None
    verdict: VerdictLabel | None
    verdict_p: float | None
    detectors: dict[str, DetectorOutcome] = field(default_factory=dict)
    error: str | None = None
    format: str | None = None
    megapixels: float | None = None
    where: dict[str, float] | None = None
    """The report's Where map (every flagged detector's map, joined) against the true mask: ``mcc``, ``iou``,
    ``f1``; None without a mask."""


# The plugins the workers use: set before the pool forks, so that every worker
# inherits the caller's host (entry points or, in tests, fixture plugins)
# without loading or pickling it again.
_HOST: PluginHost | None = None


def _scores(pred: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    return {"mcc": mcc(pred, truth), "iou": iou(pred, truth), "f1": f1(pred, truth)}


def analyse_case(case: Case, options: Options, findings_dir: Path) -> CaseResult:
    """Analyse one photo in this worker; its findings are kept in ``findings_dir`` for audit."""
    host = _HOST or PluginHost.from_entry_points()
    base = CaseResult(case.name, case.spliced, dict(case.conditions), None, None, None)
    try:
        evidence = load_evidence(case.path, max_pixels=options.max_pixels)
    except EvidenceError as exc:
        base.error = str(exc)
        return base
    findings: Findings = analyze_evidence(evidence, host, options)
    write_atomic(findings_dir / f"{case.name}.json", findings.to_json().encode("utf-8"))
    truth = load_mask(case.mask, evidence.luma.shape) if case.mask is not None else None
    where = None if truth is None or not case.spliced else np.zeros(truth.shape, dtype=bool)
    for f in findings.detectors:
        outcome = DetectorOutcome(f.status, finding_p(f), f.score, f.error, f.elapsed_s)
        if where is not None:
            pred = localise_map(host, f, truth.shape)
            if pred is not None:
                scores = _scores(pred, truth)
                outcome.mcc, outcome.iou, outcome.f1 = scores["mcc"], scores["iou"], scores["f1"]
                # The report's page 1 outlines the maps of the detectors that found something, and only those.
                if found_something(f, findings.verdict):
                    where |= pred
        base.detectors[f.name] = outcome
    if where is not None:
        base.where = {k: round(v, 6) for k, v in _scores(where, truth).items()}
    v = findings.verdict
    base.sha256, base.verdict, base.verdict_p = evidence.info.sha256, v.label, v.p_value
    base.format, base.megapixels = evidence.info.format, round(evidence.info.width * evidence.info.height / 1e6, 3)
    return base


def run_cases(
    cases: Sequence[Case],
    host: PluginHost,
    options: Options,
    findings_dir: Path,
    workers: int,
    on_done: Callable[[CaseResult], None] = lambda r: None,
) -> list[CaseResult]:
    """Analyse ``cases`` with ``workers`` processes; results in the order of ``cases``.

    A worker that dies costs only its photo, which is recorded with the error.
    """
    global _HOST
    _HOST = host
    findings_dir.mkdir(parents=True, exist_ok=True)
    results: dict[int, CaseResult] = {}
    for index, result in _pool(cases, options, findings_dir, workers):
        results[index] = result
        on_done(result)
    return [results[i] for i in range(len(cases))]


def _new_executor(workers: int) -> ProcessPoolExecutor:
    return ProcessPoolExecutor(max_workers=workers, mp_context=get_context("fork"))


def _pool(cases: Sequence[Case], options: Options, findings_dir: Path, workers: int) -> Iterator[tuple[int, CaseResult]]:
    # A dying worker breaks the whole pool and fails every photo in flight
    # without saying which one killed it; so each in-flight photo is tried
    # once more in a new pool and recorded as failed the second time.
    workers = max(1, workers)
    pending = list(range(len(cases)))
    tries = dict.fromkeys(pending, 0)
    executor = _new_executor(workers)
    running: dict[Future, int] = {}
    try:
        while pending or running:
            while pending and len(running) < 2 * workers:
                i = pending.pop(0)
                tries[i] += 1
                running[executor.submit(analyse_case, cases[i], options, findings_dir)] = i
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            broken = False
            for fut in done:
                i = running.pop(fut)
                try:
                    yield i, fut.result()
                except BrokenProcessPool:
                    broken = True
                    if tries[i] < 2:
                        pending.insert(0, i)
                    else:
                        yield i, _failed(cases[i], "the worker process died twice on this photo")
                except Exception as exc:
                    yield i, _failed(cases[i], f"internal error: {one_line(exc)}")
            if broken:
                # The others in flight were stopped by the same death: not their try.
                for i in running.values():
                    pending.insert(0, i)
                    tries[i] -= 1
                running = {}
                executor.shutdown(wait=False, cancel_futures=True)
                executor = _new_executor(workers)
    finally:
        executor.shutdown(wait=True, cancel_futures=True)


def _failed(case: Case, reason: str) -> CaseResult:
    return CaseResult(case.name, case.spliced, dict(case.conditions), None, None, None, error=reason)


def default_workers() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
