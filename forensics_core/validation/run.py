"""Running a validation: the synthetic suite, every photo through the detectors, the record and its page."""


from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

from .. import __version__
from ..analysis import Options, environment
from ..detector import implements
from ..fusion import ALPHA
from ..atomic import write_atomic
from ..plugins import PluginHost, one_line
from ..synthetic import SyntheticCase
from .cases import Suite, SuiteError, content_hash, write_synthetic
from .dependence import authentic_dependence
from .null_check import null_checks
from ..calibration.fit import calibrator_inputs, performance, supports_hp
from .record import FORMAT, Dataset, ValidationRecord, case_rows, compute_methods
from .runner import CaseResult, run_cases

SYNTHETIC = "synthetic"
RECORD_NAME = "validation.json"
THUMBNAILS = "thumbnails"


@dataclass(frozen=True)
class SyntheticProblem:
    """A detector whose synthetic cases could not be generated."""

    detector: str
    reason: str


def synthetic_suite(host: PluginHost, folder: Path, seed: int, count: int,
                    on_problem: Callable[[SyntheticProblem], None] = lambda p: None) -> Suite:
    """Generate every detector's synthetic cases into ``folder``; a detector that fails is reported and left out."""
    def generated() -> Iterator[tuple[str, SyntheticCase]]:
        for name, entry in host.detectors.items():
            if not implements(entry.detector, "synthetic_cases"):
                continue
            try:
                for case in entry.detector.synthetic_cases(seed, count) or ():
                    if not isinstance(case, SyntheticCase):
                        raise TypeError(f"yielded {type(case).__name__}, not SyntheticCase")
                    yield name, case
            except Exception as exc:
                on_problem(SyntheticProblem(name, one_line(exc)))

    cases = write_synthetic(generated(), folder)
    if not cases:
        raise SuiteError("no installed detector generated synthetic cases")
    return Suite(SYNTHETIC, f"forensics {__version__} synthetic generators", cases, content_hash(cases))


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")


def validate(
    suite: Suite,
    out: Path,
    host: PluginHost,
    options: Options,
    workers: int,
    on_done: Callable[[CaseResult], None] = lambda r: None,
    seed: int | None = None,
    count: int | None = None,
) -> ValidationRecord:
    """Analyse every case of ``suite``, then write ``validation.json`` and ``validation.html`` into ``out``."""
    started = time.perf_counter()
    options = options.resolve(host)
    params = options.detector_params
    results = run_cases(suite.cases, host, options, out / "findings", workers, on_done)
    versions = {n: d.spec.version for n, d in host.detectors.items()}
    rows = case_rows(results)
    features = calibrator_inputs(host)
    fusion = {"policy": options.fusion, "alpha": ALPHA}
    record = ValidationRecord(
        format=FORMAT,
        created=_now(),
        tool={"name": "forensics", "version": __version__},
        environment=environment(),
        dataset=Dataset(
            name=suite.name, source=suite.source, content_sha256=suite.content_sha256, n_cases=len(suite.cases),
            n_spliced=sum(c.spliced for c in suite.cases), n_authentic=sum(not c.spliced for c in suite.cases),
            failed_intake=sum(r.error is not None for r in results), seed=seed, count=count,
        ),
        fusion=fusion,
        detector_params=params,
        methods=compute_methods(results, versions, ALPHA, supports_hp(rows, features)),
        elapsed_s=round(time.perf_counter() - started, 1),
        cases=rows,
        null_checks=null_checks(rows, fusion),
        dependence=authentic_dependence(rows),
        likelihood_ratios=performance(rows, features),
    )
    write_atomic(out / RECORD_NAME, record.to_json().encode("utf-8"))
    from .page import write_page  # matplotlib: loaded only when a page is made
    from .thumbnails import conviction_thumbnails

    write_page(record, out, conviction_thumbnails(record, suite.cases, out / "findings", host, out / THUMBNAILS))
    return record
