"""The batch's record: one row per input photo, as ``summary.json`` and ``summary.csv``.

Rows keep the input order. ``outcome`` is one of:

``analysed``   analysed by this run;
``resumed``    its finished outputs from an earlier run were kept;
``duplicate``  same bytes as ``duplicate_of``, whose outputs it shares;
``failed``     ``error`` says why (one line);
``pending``    the run was interrupted before it was done.

``verdict`` is the fusion policy's label and ``log10_lr`` the fused log10
likelihood ratio of Hp (manipulation) against Hd (empty when no calibrator
applies): the label answers the triage, the likelihood ratio says how
strongly the findings support either proposition, and the two can differ
(e.g. a copy found by a detector that states no p-value).

``time_s`` is the wall-clock time the worker took (for resumed photos, as
recorded by the earlier run's summary when there is one). In the CSV, text
cells that a spreadsheet would take for a formula (starting with ``=``,
``+``, ``-``, ``@``, tab or carriage return; file names are chosen by whoever
supplied the photos) are prefixed with an apostrophe.
"""

from __future__ import annotations

import csv
import io
import json
from collections import Counter
from dataclasses import asdict, dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from .. import __version__
from ..atomic import write_atomic
from ..manifest import FINDINGS_NAME
from ..text import visible
from .plan import SUMMARY_CSV, SUMMARY_JSON

OUTCOMES = ("analysed", "resumed", "duplicate", "failed", "pending")
SUMMARY_VERSION = "1"
_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
_FIELDS = ("photo", "sha256", "outcome", "verdict", "log10_lr", "output", "duplicate_of", "time_s", "attempts", "error")


@dataclass
class Row:
    """One input photo's line of the summary; ``detectors`` maps each name to its status and score.

    ``log10_lr`` is the verdict's fused log10 likelihood ratio, as in ``findings.json``.
    """

    photo: str
    sha256: str | None
    outcome: str = "pending"
    verdict: str | None = None
    log10_lr: float | None = None
    output: str | None = None
    duplicate_of: str | None = None
    time_s: float | None = None
    attempts: int | None = None
    error: str | None = None
    detectors: dict[str, dict[str, Any]] = field(default_factory=dict)


def fill_from_findings(row: Row, folder: Path) -> bool:
    """Copy the verdict, its fused log10 LR and each detector's status and score from ``folder/findings.json``; False
    if unreadable."""
    try:
        doc = json.loads((folder / FINDINGS_NAME).read_bytes())
        row.verdict = doc["verdict"]["label"]
        row.log10_lr = doc["verdict"].get("log10_lr")
        row.detectors = {d["name"]: {"status": d["status"], "score": d["score"]} for d in doc["detectors"]}
    except (OSError, ValueError, KeyError, TypeError):
        return False
    return True


def previous_times(out_dir: Path) -> dict[tuple[str, str], float]:
    """``time_s`` of each photo in the earlier summary, keyed by (photo, sha256); empty if there is none."""
    try:
        doc = json.loads((out_dir / SUMMARY_JSON).read_bytes())
        return {(r["photo"], r["sha256"]): float(r["time_s"]) for r in doc["photos"]
                if r.get("time_s") is not None and r.get("sha256")}
    except (OSError, ValueError, KeyError, TypeError):
        return {}


def detector_names(rows: list[Row], selected: list[str]) -> list[str]:
    """The selected detectors, then any other a finding names (e.g. from a resumed earlier run)."""
    names = list(selected)
    for row in rows:
        names.extend(n for n in row.detectors if n not in names)
    return names


def _cell(value: Any) -> Any:
    # File names may hold ESC or U+202E; a spreadsheet or a terminal shows the escape, never the effect.
    if isinstance(value, str):
        value = visible(value)
    if isinstance(value, str) and value.startswith(_FORMULA_START):
        return "'" + value
    return "" if value is None else value


def to_csv(rows: list[Row], detectors: list[str]) -> bytes:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([*_FIELDS, *(f"{d}.{k}" for d in detectors for k in ("status", "score"))])
    for row in rows:
        cells = [getattr(row, f) for f in _FIELDS]
        for name in detectors:
            entry = row.detectors.get(name, {})
            cells.extend((entry.get("status"), entry.get("score")))
        writer.writerow([_cell(c) for c in cells])
    return buffer.getvalue().encode("utf-8")


def counts(rows: list[Row]) -> dict[str, Any]:
    outcome = Counter(r.outcome for r in rows)
    verdict = Counter(r.verdict for r in rows if r.verdict is not None)
    return {"photos": len(rows), **{o: outcome.get(o, 0) for o in OUTCOMES}, "verdicts": dict(sorted(verdict.items()))}


def write_summary(out_dir: Path, rows: list[Row], detectors: list[str], run: dict[str, Any]) -> tuple[Path, Path]:
    """Write ``summary.csv`` and ``summary.json`` (each atomically) into ``out_dir``.

    Parameters
    ----------
    out_dir : Path
    rows : list of Row
    detectors : list of str
        Column order of the detectors.
    run : dict
        How the batch ran (inputs, workers, settings, peak memory), recorded as is.
    """
    created = datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")
    doc = {
        "summary_version": SUMMARY_VERSION,
        "tool": {"name": "forensics", "version": __version__},
        "created": created,
        "run": run,
        "counts": counts(rows),
        "detectors": detectors,
        "photos": [asdict(r) for r in rows],
    }
    csv_path = write_atomic(out_dir / SUMMARY_CSV, to_csv(rows, detectors))
    json_path = write_atomic(out_dir / SUMMARY_JSON,
                             (json.dumps(doc, indent=2, ensure_ascii=False, allow_nan=False) + "\n").encode("utf-8"))
    return json_path, csv_path
