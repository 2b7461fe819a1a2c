"""The work one worker does for one photo, wherever the worker runs.

A worker keeps the loaded plugins and the signing key for its lifetime.
Local workers are forked from the command and inherit both (the private key
never leaves the machine's memory); Dask workers load the plugins installed
where they run and the key from the path the command used (``--key`` or the
per-user key), with the password from their own environment, and check that
it is the same certificate.
"""

from __future__ import annotations

import multiprocessing
import os
import resource
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..analysis import Options
from ..evidence import Evidence, EvidenceError
from ..findings import Findings
from ..output import Placement, owned_placement
from ..pipeline import ReportError, ReportSettings, examine_photo
from ..plugins import PluginHost, one_line
from ..report.render import ReportOptions
from ..defaults import PASSWORD_ENV
from ..signing import ExaminerKey, SigningError, load_key
from .plan import Job

_state: dict[str, Any] = {}


@dataclass(frozen=True)
class Settings:
    """Everything a worker needs besides the photo; picklable, and free of secrets.

    Attributes
    ----------
    options : Options
        Detectors (an explicit list), parameters, time limit, isolation.
    report_formats : tuple of {"html", "pdf"}
        Empty for JSON only.
    report_options : ReportOptions
    organisation, tsa_url : str or None
    key_path : str or None
        Absolute path of the signing key, for workers that load it themselves.
    key_fingerprint : str or None
        SHA-256 fingerprint of its certificate, checked by those workers.
    """

    options: Options
    report_formats: tuple[str, ...] = ()
    report_options: ReportOptions = field(default_factory=ReportOptions)
    organisation: str | None = None
    tsa_url: str | None = None
    key_path: str | None = None
    key_fingerprint: str | None = None


@dataclass(frozen=True)
class PhotoOutcome:
    """What a worker reports for one photo.

    Attributes
    ----------
    error : str or None
        One-line reason the photo failed, else None.
    verdict : str or None
        The verdict label.
    log10_lr : float or None
        The fused log10 likelihood ratio (None when no calibrator applies).
    detectors : tuple of (name, status, score)
    seconds : float
        Wall-clock time on the worker.
    refused_urls : tuple of str
        URLs the PDF renderer was refused (normally none).
    worker_peak_mb, child_peak_mb : float or None
        Peak resident memory so far of the worker process and of its largest
        finished detector child (Linux; None elsewhere).
    """

    error: str | None
    verdict: str | None = None
    log10_lr: float | None = None
    detectors: tuple[tuple[str, str, float | None], ...] = ()
    seconds: float = 0.0
    refused_urls: tuple[str, ...] = ()
    worker_peak_mb: float | None = None
    child_peak_mb: float | None = None


def preload(host: PluginHost, key: ExaminerKey | None) -> None:
    """Set this process's plugins and key; local workers forked afterwards inherit them."""
    _state["host"] = host
    _state["key"] = key


def _host() -> PluginHost:
    if "host" not in _state:
        _state["host"] = PluginHost.from_entry_points()
    return _state["host"]


def _key(settings: Settings) -> ExaminerKey:
    key = _state.get("key")
    if key is None:
        password = os.environ.get(PASSWORD_ENV)
        key = load_key(Path(settings.key_path), password.encode("utf-8") if password is not None else None)
        _state["key"] = key
    if key.fingerprint != settings.key_fingerprint:
        raise SigningError(f"the key {key.source} on this worker is not the certificate the batch was started "
                           f"with (SHA-256 {settings.key_fingerprint})")
    return key


def _peaks_mb() -> tuple[float | None, float | None]:
    # ru_maxrss is in KiB on Linux (bytes on macOS, where the figure is not used).
    if not sys.platform.startswith("linux"):
        return None, None
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return round(own, 1), round(children, 1)


def _allow_detector_children() -> None:
    # A Dask nanny starts its worker as a daemonic process, and multiprocessing
    # refuses to start children from one; the detectors' time limits and crash
    # containment need a forked child per detector. Detector children end at
    # their own time limit, so none outlives the worker for long.
    current = multiprocessing.current_process()
    if current.daemon:
        current.daemon = False


def process_photo(job: Job, settings: Settings) -> PhotoOutcome:
    """Analyse one photo and write its outputs; never raises.

    The photo must still have the bytes the batch hashed. The bundle is made
    in a hidden folder and renamed onto the photo's, whatever that holds, so
    a worker killed at any moment leaves the folder as it was.
    """
    started = time.perf_counter()
    folder = Path(job.folder)

    def place(evidence: Evidence, findings: Findings) -> Placement:
        if evidence.info.sha256 != job.sha256:
            raise EvidenceError("changed while the batch ran (its SHA-256 is not the one taken at the start)")
        return owned_placement(folder)

    done = None
    error: str | None = None
    try:
        if settings.options.isolation == "process":
            _allow_detector_children()
        report = None
        if settings.report_formats:
            report = ReportSettings(_key(settings), settings.report_formats, settings.report_options,
                                    settings.organisation, settings.tsa_url)
        done = examine_photo(Path(job.path), place, _host(), settings.options, report)
    except EvidenceError as exc:
        error = str(exc)
    except SigningError as exc:
        error = f"cannot sign: {exc}"
    except OSError as exc:
        error = f"cannot write output: {exc.strerror or exc}"
    except ReportError as exc:
        error = f"cannot write the report: {exc}"
    except Exception as exc:  # a bug must cost this photo only, not the batch
        error = f"internal error: {one_line(exc)}"
    worker_mb, child_mb = _peaks_mb()
    seconds = round(time.perf_counter() - started, 3)
    if done is None:
        return PhotoOutcome(error=error, seconds=seconds, worker_peak_mb=worker_mb, child_peak_mb=child_mb)
    findings = done.findings
    return PhotoOutcome(
        error=findings.evidence.changed_during_analysis,
        verdict=findings.verdict.label.value,
        log10_lr=findings.verdict.log10_lr,
        detectors=tuple((d.name, d.status.value, d.score) for d in findings.detectors),
        seconds=seconds,
        refused_urls=tuple(done.refused_urls),
        worker_peak_mb=worker_mb,
        child_peak_mb=child_mb,
    )
