"""Run the selected detectors on one photo and assemble its findings.

Each detector runs in a forked child process by default: a hang is ended at
the time limit, a crash (even a segfault in native code) costs only that
detector, and nothing the plugin does can alter the parent's copy of the
evidence. Where ``fork`` is unavailable, or with ``isolation="inline"``, the
detector runs in a thread of this process; a time limit is then reported but
the runaway thread cannot be stopped.
"""

from __future__ import annotations

import os
import platform
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from datetime import datetime, timezone
from importlib.metadata import PackageNotFoundError, version
from typing import Any

from PIL import features

from . import __version__
from .evidence import Evidence, load_evidence
from .findings import (
    SCHEMA_VERSION,
    DetectorFinding,
    DetectorResult,
    DetectorSpec,
    Findings,
    MalformedResult,
    Status,
    Tool,
    Verdict,
    VerdictLabel,
    check_result,
    to_jsonable,
)
from .containment import Child, can_fork, jobs_for, run_forked, run_threaded, wait_any
from .defaults import DEFAULT_MAX_PIXELS, DEFAULT_TIMEOUT_S, ISOLATIONS
from .evaluation import calibration_file, decide_by_lr, evaluate
from .fusion import POLICY as DEFAULT_FUSION
from .plugins import PluginHost, one_line
from .reference import ReferenceSet, references_for

# The numerical packages the bundled detectors compute with, any of which may move their last digits: the same code
# on two machines whose listed versions agreed before OpenCV, jpeglib and PyWavelets were listed gave copy_move
# scores 1e-4 apart on 16 of the real corpus's 395 photos.
_ENV_PACKAGES = ("numpy", "scipy", "scikit-image", "pillow", "pluggy", "numba", "opencv-python-headless", "jpeglib",
                 "PyWavelets")


@dataclass(frozen=True)
class Options:
    """How an analysis runs; recorded as ``parameters`` in the findings.

    Parameters
    ----------
    detectors : sequence of str or None
        Detector names to run; None runs every registered detector.
    timeout_s : float
        Wall-clock limit per detector, seconds.
    max_pixels : int
        Pixel-count limit of the intake (decompression bombs).
    fusion : str
        Name of the fusion policy.
    isolation : {"process", "inline"}
    detector_params : mapping of str to mapping
        Per-detector overrides of the default parameters.
    case_id, examiner : str or None
        Case information carried into the findings.
    calibration : str or None
        Path of the likelihood-ratio calibrators (``forensics calibrate``);
        None for those shipped with the tool.
    reference : str or None
        Folder of reference photos of the claimed camera
        (:mod:`~forensics_core.reference`), for detectors whose spec
        ``uses_reference``; None for none.
    jobs : int
        Detectors run at once, each in its own process (``isolation="process"``
        only; one at a time above :data:`~forensics_core.defaults.PARALLEL_MAX_PIXELS`).
        Not recorded: it changes how long a run takes, not its findings.
    resolved : bool
        Set by :meth:`resolve`: ``detectors`` names every detector to run and
        ``detector_params`` holds each one's complete parameters.
    """

    detectors: Sequence[str] | None = None
    timeout_s: float = DEFAULT_TIMEOUT_S
    max_pixels: int = DEFAULT_MAX_PIXELS
    fusion: str = DEFAULT_FUSION
    isolation: str = "process"
    detector_params: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    case_id: str | None = None
    examiner: str | None = None
    calibration: str | None = None
    reference: str | None = None
    jobs: int = 1
    resolved: bool = False

    def resolve(self, host: PluginHost) -> Options:
        """These options with the detectors named and their parameters resolved (:func:`resolve_params`).

        Done once for a run, however many photos it takes; resolving resolved
        options returns them unchanged.

        Raises
        ------
        ValueError
            As :func:`resolve_params`.
        """
        if self.resolved:
            return self
        selected = list(self.detectors) if self.detectors is not None else sorted(host.detectors)
        return replace(self, detectors=selected, detector_params=resolve_params(host, self), resolved=True)


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")


def environment() -> dict[str, Any]:
    """Python, platform and the versions of the numerical packages, as every findings record states them."""
    packages = {}
    for name in _ENV_PACKAGES:
        try:
            packages[name] = version(name)
        except PackageNotFoundError:
            packages[name] = None
    # The JPEG decoder fixes the pixels every detector reads: another version
    # (a Pillow built against the system's library) may round the inverse DCT
    # and the chroma upsampling differently.
    packages["libjpeg-turbo"] = features.version("libjpeg_turbo")
    return {
        "python": platform.python_version(),
        "implementation": platform.python_implementation(),
        "platform": platform.platform(),
        "machine": platform.machine(),
        "packages": packages,
    }


def resolve_params(host: PluginHost, options: Options) -> dict[str, dict[str, Any]]:
    """Each selected detector's defaults merged with the user's overrides.

    Raises
    ------
    ValueError
        For overrides of a detector that does not exist or of a parameter the
        detector does not declare: a misspelt parameter must not pass silently.
    """
    selected = list(options.detectors) if options.detectors is not None else sorted(host.detectors)
    for name, overrides in options.detector_params.items():
        if name not in host.detectors:
            raise ValueError(f"parameters given for unknown detector {name!r}")
        unknown = sorted(set(overrides) - set(host.detectors[name].spec.default_params))
        if unknown:
            known = ", ".join(sorted(host.detectors[name].spec.default_params)) or "none"
            raise ValueError(f"{name} has no parameter {', '.join(unknown)} (known: {known})")
    return {
        name: {**host.detectors[name].spec.default_params, **options.detector_params.get(name, {})}
        for name in selected
        if name in host.detectors
    }


@dataclass(frozen=True)
class _Job:
    """A detector ready to run: what its finding is made of, and the call that runs it."""

    spec: DetectorSpec
    plugin: str
    params: dict[str, Any]
    call: Callable[[], Any]


def _not_run(spec: DetectorSpec, plugin: str, params: dict[str, Any], status: Status, summary: str, *,
             details: dict[str, Any] | None = None, error: str | None = None, elapsed_s: float = 0.0,
             output: str | None = None) -> DetectorFinding:
    """The finding of a detector that gave no result: skipped, unavailable or failed."""
    return DetectorFinding(name=spec.name, version=spec.version, plugin=plugin, status=status, summary=summary,
                           score=None, p_value=None, nfa=None, details=details or {}, parameters=params,
                           elapsed_s=elapsed_s, error=error, output=output)


def _job(host: PluginHost, name: str, evidence: Evidence, params: dict[str, Any],
         prior: Mapping[str, DetectorFinding] | None, reference: ReferenceSet | None = None) -> _Job | DetectorFinding:
    """The detector's job, or its finding when it cannot or need not run (not installed, another format)."""
    registered = host.detectors.get(name)
    if registered is None:
        available = ", ".join(sorted(host.detectors)) or "none"
        failed = [r.name for r in host.plugin_records() if r.status == "error"]
        hint = f"; plugins that failed to load: {', '.join(failed)}" if failed else ""
        return _not_run(DetectorSpec(name, "unknown", ""), "unknown", params, Status.ERROR,
                        "The detector is not available.",
                        error=f"no loaded plugin provides detector {name!r} (available: {available}){hint}")
    spec, plugin, detector = registered.spec, registered.plugin, registered.detector
    fmt = evidence.info.format
    if spec.formats and fmt not in spec.formats:
        return _not_run(spec, plugin, params, Status.SKIPPED,
                        f"Not applied to a {fmt} file: the detector applies to {', '.join(spec.formats)} files, the "
                        f"formats its null model was checked on.", details={"formats": list(spec.formats)})
    if spec.uses_reference and reference is None:
        return _not_run(spec, plugin, params, Status.SKIPPED,
                        "Not applied: no reference photos of the claimed camera were given (--reference DIR).")
    seen = {n: f for n, f in (prior or {}).items() if n in spec.uses}
    extra: dict[str, Any] = {"reference": reference} if spec.uses_reference else {}
    if registered.reads_prior:
        extra["prior"] = seen

    def call() -> Any:
        return detector.analyze(evidence, dict(params), **extra)

    return _Job(spec, plugin, params, call)


def _finding(job: _Job, outcome: tuple, printed: str | None, elapsed_s: float) -> DetectorFinding:
    """The finding of a job from its contained outcome."""
    spec, elapsed = job.spec, round(elapsed_s, 3)

    def failed(reason: str, details: dict[str, Any] | None = None) -> DetectorFinding:
        return _not_run(spec, job.plugin, job.params, Status.ERROR, "The detector failed; see error.",
                        details=details, error=reason, elapsed_s=elapsed, output=printed)

    if outcome[0] == "error":
        return failed(outcome[1], {"traceback": outcome[2]} if outcome[2] else None)
    try:
        result: DetectorResult = check_result(outcome[1])
    except MalformedResult as exc:
        return failed(f"malformed result: {exc}")
    return DetectorFinding(name=spec.name, version=spec.version, plugin=job.plugin, status=result.status,
                           summary=result.summary, score=result.score, p_value=result.p_value, nfa=result.nfa,
                           details=result.details, parameters=job.params, elapsed_s=elapsed, output=printed,
                           headline=result.headline, log10_lr=result.log10_lr)


def run_detector(
    host: PluginHost,
    name: str,
    evidence: Evidence,
    params: dict[str, Any],
    options: Options,
    prior: Mapping[str, DetectorFinding] | None = None,
    reference: ReferenceSet | None = None,
) -> DetectorFinding:
    """Run one detector with containment; always returns a finding.

    ``prior`` holds findings of this run; the detector sees those its spec
    ``uses``. ``reference`` goes to a detector whose spec ``uses_reference``.
    """
    job = _job(host, name, evidence, params, prior, reference)
    if isinstance(job, DetectorFinding):
        return job
    host.prepare(name)
    started = time.perf_counter()
    printed: str | None = None
    if options.isolation == "process" and can_fork():
        outcome, printed = run_forked(job.call, options.timeout_s)
    else:
        outcome = run_threaded(job.call, options.timeout_s)
    return _finding(job, outcome, printed, time.perf_counter() - started)


def detector_jobs(options: Options, evidence: Evidence) -> int:
    """How many detectors run at once on this photo (:func:`~forensics_core.containment.jobs_for`; one inline)."""
    if options.isolation != "process":
        return 1
    return jobs_for(evidence.info.width * evidence.info.height, options.jobs)


def run_detectors(host: PluginHost, order: Sequence[str], evidence: Evidence, params: Mapping[str, dict[str, Any]],
                  options: Options, jobs: int = 1,
                  reference: ReferenceSet | None = None) -> dict[str, DetectorFinding]:
    """Run the detectors of ``order`` (from :func:`run_order`), ``jobs`` at a time; a finding for each.

    A detector starts once those it ``uses`` have finished, so it sees their
    findings as it would in a run one at a time; the findings do not depend
    on ``jobs``, only the elapsed times do.
    """
    done: dict[str, DetectorFinding] = {}
    if jobs <= 1:
        for name in order:
            done[name] = run_detector(host, name, evidence, params.get(name, {}), options, prior=done,
                                      reference=reference)
        return done
    chosen = set(order)
    pending = list(order)
    running: dict[Child, tuple[str, _Job]] = {}

    def ready(name: str) -> bool:
        registered = host.detectors.get(name)
        return all(dep in done for dep in (registered.spec.uses if registered else ()) if dep in chosen)

    while pending or running:
        while pending and len(running) < jobs:
            # A cycle of ``uses`` is broken by the order, as run_order does.
            name = next((n for n in pending if ready(n)), None if running else pending[0])
            if name is None:
                break
            pending.remove(name)
            job = _job(host, name, evidence, params.get(name, {}), done, reference)
            if isinstance(job, DetectorFinding):
                done[name] = job
            else:
                host.prepare(name)
                running[Child(job.call, options.timeout_s)] = (name, job)
        if running:
            # The next detector's imports, while the running ones compute.
            upcoming = next((n for n in pending if n in host.detectors), None)
            if upcoming is not None:
                host.prepare(upcoming)
            for child in wait_any(list(running)):
                name, job = running.pop(child)
                outcome, printed = child.collect()
                done[name] = _finding(job, outcome, printed, time.monotonic() - child.started)
    return done


def _extra_metadata(host: PluginHost, evidence: Evidence, contained_s: float | None) -> dict[str, Any]:
    extra: dict[str, Any] = {}
    for outcome in host.each("forensics_extract_metadata", contained_s=contained_s, evidence=evidence):
        if outcome.error is not None:
            extra[outcome.plugin] = {"error": one_line(outcome.error)}
        elif outcome.value is not None:
            try:
                extra[outcome.plugin] = to_jsonable(dict(outcome.value), f"{outcome.plugin} metadata")
            except (MalformedResult, TypeError, ValueError) as exc:
                extra[outcome.plugin] = {"error": f"malformed metadata: {exc}"}
    return extra


def fuse(host: PluginHost, policy: str, findings: Sequence[DetectorFinding], evidence: Evidence) -> Verdict:
    """The verdict of ``forensics_fuse``, called through pluggy: the first plugin to implement ``policy`` decides.

    An implementation that raises is left out of the call (it may not
    implement ``policy`` at all, and must not spoil the verdict of the
    plugin that does). Only when no plugin gives a verdict are the failures
    stated, as the reason the verdict is inconclusive.
    """
    call = host.call("forensics_fuse", policy=policy, findings=findings, evidence=evidence)
    if isinstance(call.value, Verdict):
        return call.value
    failures = [f"plugin {f.plugin!r} failed: {one_line(f.error)}" for f in call.failures]
    if call.value is not None:
        failures.append(f"the first answer was a {type(call.value).__name__}, not a Verdict")
    if failures:
        return Verdict(VerdictLabel.INCONCLUSIVE, None,
                       f"No verdict by fusion policy {policy!r}: " + "; ".join(failures) + ".", policy)
    return Verdict(VerdictLabel.INCONCLUSIVE, None, f"No installed plugin implements fusion policy {policy!r}.", policy)


def run_order(host: PluginHost, selected: Sequence[str]) -> list[str]:
    """``selected`` reordered so that each detector runs after those it ``uses``.

    Otherwise the given order is kept; a cycle of ``uses`` is broken by that order.
    """
    chosen = set(selected)
    order: list[str] = []
    visiting: set[str] = set()

    def visit(name: str) -> None:
        if name in order or name in visiting:
            return
        visiting.add(name)
        registered = host.detectors.get(name)
        for dep in registered.spec.uses if registered else ():
            if dep in chosen:
                visit(dep)
        order.append(name)

    for name in selected:
        visit(name)
    return order


def analyze_evidence(evidence: Evidence, host: PluginHost, options: Options) -> Findings:
    """Run the selected detectors on already loaded evidence."""
    if options.isolation not in ISOLATIONS:
        raise ValueError(f"isolation must be one of {', '.join(ISOLATIONS)}")
    options = options.resolve(host)
    params = options.detector_params
    selected = list(options.detectors)
    contained = options.timeout_s if options.isolation == "process" else None
    evidence.info.extra_metadata = _extra_metadata(host, evidence, contained)
    reference = references_for(options.reference, options.max_pixels) if options.reference else None
    done = run_detectors(host, run_order(host, selected), evidence, params, options,
                         detector_jobs(options, evidence), reference)
    findings = [done[name] for name in selected]
    verdict = fuse(host, options.fusion, findings, evidence)
    evaluate(findings, verdict, evidence.info, calibration_file(options.calibration))
    decide_by_lr(verdict)
    return Findings(
        schema_version=SCHEMA_VERSION,
        tool=Tool("forensics", __version__),
        created=_now(),
        evidence=evidence.info,
        parameters={
            "detectors": selected,
            "timeout_s": options.timeout_s,
            "max_pixels": options.max_pixels,
            "fusion": options.fusion,
            "isolation": options.isolation,
            "detector_params": {name: dict(values) for name, values in params.items()},
            "case_id": options.case_id,
            "examiner": options.examiner,
            "calibration": options.calibration,
            "reference": options.reference,
        },
        environment=environment(),
        plugins=host.plugin_records(),
        detectors=findings,
        verdict=verdict,
        references=reference.records if reference else [],
    )


def analyze(
    path: str | os.PathLike[str],
    detectors: Sequence[str] | None = None,
    *,
    host: PluginHost | None = None,
    timeout: float = DEFAULT_TIMEOUT_S,
    max_pixels: int = DEFAULT_MAX_PIXELS,
    fusion: str = DEFAULT_FUSION,
    isolation: str = "process",
    case_id: str | None = None,
    examiner: str | None = None,
    jobs: int = 1,
    reference: str | os.PathLike[str] | None = None,
    **params: Mapping[str, Any],
) -> Findings:
    """Analyse one photo and return its findings.

    Parameters
    ----------
    path : path-like
        The evidence photo (read, never written).
    detectors : sequence of str, optional
        Detectors to run; default all installed.
    host : PluginHost, optional
        Loaded plugins; default: load the installed entry points.
    timeout, max_pixels, fusion, isolation, case_id, examiner, jobs, reference
        See :class:`Options`.
    **params : mapping
        Per-detector parameter overrides, keyed by detector name, e.g.
        ``analyze(p, lens_distortion={"estimator": "paper"})``.

    Raises
    ------
    forensics_core.EvidenceError
        When the file cannot be taken in.
    ValueError
        For unknown parameters.

    Examples
    --------
    >>> import forensics_core
    >>> findings = forensics_core.analyze("tests/data/calibration/left01.jpg", ["lens_distortion"])
    >>> findings.detectors[0].name, findings.verdict.label.value
    ('lens_distortion', 'consistent')
    """
    host = host or PluginHost.from_entry_points()
    evidence = load_evidence(path, max_pixels=max_pixels)
    options = Options(
        detectors=list(detectors) if detectors is not None else None,
        timeout_s=timeout,
        max_pixels=max_pixels,
        fusion=fusion,
        isolation=isolation,
        detector_params={k: dict(v) for k, v in params.items()},
        case_id=case_id,
        examiner=examiner,
        jobs=jobs,
        reference=os.fspath(reference) if reference is not None else None,
    )
    return analyze_evidence(evidence, host, options)


__all__ = ["Options", "analyze", "analyze_evidence", "detector_jobs", "fuse", "resolve_params", "run_detector",
           "run_detectors", "run_order"]
