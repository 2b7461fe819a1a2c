"""Where a photo's outputs go: its folder, never one holding another photo's or other settings' outputs."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from .atomic import write_atomic
from .findings import Findings
from .manifest import FINDINGS_NAME


@dataclass(frozen=True)
class Placement:
    """Where one photo's outputs go.

    Attributes
    ----------
    folder : Path
    action : {"new", "kept", "replace"}
        ``new``: an empty or absent folder; ``kept``: it already holds this
        photo's outputs made with the same settings, left untouched;
        ``replace``: it holds this photo's outputs and ``--force`` asked for
        them to be replaced, as a whole and atomically.
    """

    folder: Path
    action: str = "new"


def _prior(folder: Path) -> tuple[str | None, object, set[str]] | None:
    """(evidence SHA-256, parameters, file names) of the outputs in ``folder``; None when it holds no findings."""
    try:
        doc = json.loads((folder / FINDINGS_NAME).read_text(encoding="utf-8"))
        return doc["evidence"]["sha256"], doc.get("parameters"), {p.name for p in folder.iterdir()}
    except (OSError, ValueError, KeyError, TypeError, RecursionError):
        return None


def place_outputs(out_dir: Path, photo: Path, findings: Findings, files: set[str], used: set[str],
                  force: bool = False) -> Placement:
    """The folder for one photo's outputs, never one that holds another photo's or other settings' outputs.

    Tried in turn: ``<stem>``, ``<stem>-<first 12 hex of SHA-256>``, then
    that with ``-2``, ``-3``, ... A folder that is absent or empty is taken;
    one holding this photo's outputs with the same parameters and at least
    ``files`` is kept as it is (or replaced with ``force``); anything else
    (another photo, other settings, unreadable findings, stray files) is
    passed over.
    """
    sha = findings.evidence.sha256
    stem = photo.stem or "photo"
    names = [stem, f"{stem}-{sha[:12]}"] + [f"{stem}-{sha[:12]}-{i}" for i in range(2, 1000)]
    for name in names:
        if name in used:
            continue
        folder = out_dir / name
        if not folder.exists() or (folder.is_dir() and not any(folder.iterdir())):
            used.add(name)
            return Placement(folder)
        prior = _prior(folder) if folder.is_dir() else None
        if prior is None or prior[0] != sha:
            continue
        same = prior[1] == json.loads(findings.to_json())["parameters"] and files <= prior[2]
        if force or same:
            used.add(name)
            return Placement(folder, "replace" if force else "kept")
    raise OSError(f"no free output folder for {stem} in {out_dir}")


def write_findings(findings: Findings, folder: Path) -> Path:
    return write_atomic(folder / FINDINGS_NAME, findings.to_json().encode("utf-8"))
