"""Where and how outputs are written: per-photo folders, atomic writes."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from .findings import Findings

FINDINGS_NAME = "findings.json"


def output_dir_for(out_dir: Path, photo: Path, sha256: str, used: set[str]) -> Path:
    """``out_dir/<photo stem>``, or ``<stem>-<first 12 hex of sha256>`` when the stem is taken in this run."""
    stem = photo.stem or "photo"
    name = stem if stem not in used else f"{stem}-{sha256[:12]}"
    used.add(name)
    return out_dir / name


def write_atomic(path: Path, data: bytes) -> Path:
    """Write ``data`` to a temporary file beside ``path``, then rename it into place.

    A run stopped at any moment leaves either the old file or the new one,
    never half of one.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_findings(findings: Findings, folder: Path) -> Path:
    return write_atomic(folder / FINDINGS_NAME, findings.to_json().encode("utf-8"))
