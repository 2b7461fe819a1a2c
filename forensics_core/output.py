"""Where a photo's outputs go: its folder, never one holding another photo's or other settings' outputs."""

from __future__ import annotations

import errno
import fcntl
import json
import os
import secrets
import shutil
from collections.abc import Callable, Iterator
from contextlib import contextmanager
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
        ``new``: an empty or absent folder, which the bundle, made whole
        beside it, takes by one rename (see :func:`publish`); ``kept``: it
        already holds this photo's outputs made with the same settings, left
        untouched; ``replace``: it holds this photo's outputs and ``--force``
        asked for them to be replaced, as a whole and atomically (``forensics
        batch`` replaces whatever a folder it owns holds: an unfinished
        bundle, a link to a duplicate's).
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


def _free(folder: Path) -> bool:
    """True when ``folder`` is absent or an empty real folder: a bundle can be renamed onto it."""
    if not os.path.lexists(folder):
        return True
    return folder.is_dir() and not folder.is_symlink() and not any(folder.iterdir())


def owned_placement(folder: Path) -> Placement:
    """The placement of a bundle in a folder the caller owns (``forensics batch``), whatever the folder holds."""
    return Placement(folder, "new" if _free(folder) else "replace")


def place_outputs(out_dir: Path, photo: Path, findings: Findings, files: set[str], used: set[str],
                  force: bool = False) -> Placement:
    """The folder for one photo's outputs, never one that holds another photo's or other settings' outputs.

    Tried in turn: ``<stem>``, ``<stem>-<first 12 hex of SHA-256>``, then
    that with ``-2``, ``-3``, ... A folder that is absent or empty is taken;
    one holding this photo's outputs with the same parameters and at least
    ``files`` is kept as it is (or replaced with ``force``); anything else
    (another photo, other settings, unreadable findings, stray files, a
    symbolic link to an empty folder) is passed over, and so are the names in
    ``used`` (given to earlier photos of this run).
    """
    sha = findings.evidence.sha256
    stem = photo.stem or "photo"
    names = [stem, f"{stem}-{sha[:12]}"] + [f"{stem}-{sha[:12]}-{i}" for i in range(2, 1000)]
    for name in names:
        if name in used:
            continue
        folder = out_dir / name
        if _free(folder):
            return Placement(folder)
        prior = _prior(folder) if folder.is_dir() else None
        if prior is None or prior[0] != sha:
            continue
        same = prior[1] == json.loads(findings.to_json())["parameters"] and files <= prior[2]
        if force or same:
            return Placement(folder, "replace" if force else "kept")
    raise OSError(f"no free output folder for {stem} in {out_dir}")


@contextmanager
def staging_folder(folder: Path) -> Iterator[Path]:
    """A new hidden folder beside ``folder``, ``.<name>.<8 hex>.tmp``, to make a bundle in before it is published.

    The name is the one :func:`forensics_core.batch.resume.is_temp_name`
    recognises, so ``forensics batch`` removes those a killed run left. While
    the block runs the folder is locked (``flock`` on the folder itself, which
    ends with the process however it ends), and ``forensics batch`` into the
    same output folder passes over it: an ``analyze`` under way there keeps
    the folder it is writing in.
    """
    folder.parent.mkdir(parents=True, exist_ok=True)
    staging = folder.parent / f".{folder.name}.{secrets.token_hex(4)}.tmp"
    staging.mkdir()
    fd = os.open(staging, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield staging
    finally:
        os.close(fd)


def _swap(staging: Path, folder: Path) -> None:
    """Put the bundle made in ``staging`` in the place of the one in ``folder``, which is then deleted.

    When the new bundle cannot take the place, the old one is put back; if
    another run's bundle has taken the place meanwhile, the old one is left
    aside in a staging folder rather than deleted.
    """
    with staging_folder(folder) as aside:
        try:
            os.rename(folder, aside / folder.name)
        except OSError:
            aside.rmdir()
            raise
        try:
            os.rename(staging, folder)
        except OSError:
            os.rename(aside / folder.name, folder)
            aside.rmdir()
            raise
        shutil.rmtree(aside, ignore_errors=True)


def publish(staging: Path, placement: Placement, place_again: Callable[[], Placement]) -> Placement:
    """Rename the finished bundle in ``staging`` onto ``placement.folder``; return where it went, or ``kept``.

    Two runs of one photo into one output folder may both find the same
    folder free. The folder is claimed by the rename that publishes a whole
    bundle, which only one run can do (a folder holding files cannot be
    renamed onto), so no finished bundle is overwritten or mixed with
    another, and none is ever seen half made. The run that loses places its
    bundle again by the usual rules, now that the winner's is there: kept
    when it has the same photo and settings, as if the runs had been one
    after the other, else under the next name. Waiting on a lock instead
    would tie a run to another's lifetime (a hung time-stamping service),
    and a lock file outlives a run killed outright; failing would make the
    examiner rerun only to be told the outputs are kept. A killed run leaves
    the folder free: its hidden staging folder holds no claim.

    Returns
    -------
    Placement
        The placement that took effect; when it is ``kept``, ``staging`` is
        left for the caller to delete.
    """
    while placement.action != "kept":
        try:
            if placement.action == "replace":
                _swap(staging, placement.folder)
            else:
                os.rename(staging, placement.folder)
            return placement
        except OSError as exc:
            if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST):
                raise
        placement = place_again()
    return placement


def write_findings(findings: Findings, folder: Path) -> Path:
    return write_atomic(folder / FINDINGS_NAME, findings.to_json().encode("utf-8"))
