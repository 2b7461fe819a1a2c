"""What a batch finds in its output folder: finished photos, leftovers of a killed run, the lock.

A photo's folder is complete when its marker file is there and agrees with
the photo and the settings: ``findings.json`` for JSON only, else
``manifest.json.p7s``, which the report bundle writes last (after
``manifest.json``). Every file is written to a temporary name and renamed
into place, so a run killed at any moment leaves whole files and, at worst,
temporary ``.NAME.XXXXXXXX.tmp`` files, which the next run removes.
"""

from __future__ import annotations

import fcntl
import json
import os
import re
import secrets
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..manifest import HTML_NAME, MANIFEST_NAME, PDF_NAME, SIGNATURE_NAME, sha256_file
from ..manifest import FINDINGS_NAME

LOCK_NAME = ".forensics-batch.lock"
FOREIGN = "foreign"
"""What :func:`recorded_sha` says of a path that holds something other than a photo's outputs."""

# write_atomic's temporary names: tempfile.mkstemp(prefix=".NAME.", suffix=".tmp").
_TEMP = re.compile(r"^\..+\.[a-z0-9_]{8}\.tmp$")
_REPORT_FILES = {"html": HTML_NAME, "pdf": PDF_NAME}
_COMPARED_PARAMETERS = ("detectors", "detector_params", "fusion", "case_id", "examiner", "reference")


@dataclass(frozen=True)
class Expected:
    """What a finished folder must show to be kept by a rerun.

    Attributes
    ----------
    report_formats : tuple of {"html", "pdf"}
        Empty for JSON only.
    parameters : dict
        The findings' ``detectors``, ``detector_params``, ``fusion``,
        ``case_id`` and ``examiner`` as this run would record them.
    exhibit_id : str or None
        Printed on the report, recorded in the manifest.
    """

    report_formats: tuple[str, ...]
    parameters: dict[str, Any]
    exhibit_id: str | None


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_bytes())
    except (OSError, ValueError):
        return None


def _get(doc: Any, *keys: str) -> Any:
    for key in keys:
        if not isinstance(doc, dict):
            return None
        doc = doc.get(key)
    return doc


def is_temp_name(name: str) -> bool:
    return bool(_TEMP.match(name))


def recorded_sha(folder: Path) -> str | None:
    """The SHA-256 of the photo whose outputs ``folder`` holds.

    Returns
    -------
    str or None
        The hash; None when the folder is free (absent, a broken link, or
        holding only temporary files of a killed run); :data:`FOREIGN` when it holds
        anything else (a file, an unreadable findings.json, someone's folder).
    """
    if not os.path.lexists(folder) or (folder.is_symlink() and not folder.exists()):
        return None
    if not folder.is_dir():
        return FOREIGN
    doc = _read_json(folder / FINDINGS_NAME)
    if doc is not None:
        sha = _get(doc, "evidence", "sha256")
        return sha if isinstance(sha, str) else FOREIGN
    try:
        names = os.listdir(folder)
    except OSError:
        return FOREIGN
    return None if all(is_temp_name(n) for n in names) else FOREIGN


def _normalised(value: Any) -> Any:
    return json.loads(json.dumps(value))


def is_complete(folder: Path, sha256: str, expected: Expected) -> bool:
    """True when ``folder`` holds the finished outputs of the photo ``sha256`` made with ``expected`` settings.

    Parameters
    ----------
    folder : Path
        The photo's output folder (a symbolic link to another photo's folder counts).
    sha256 : str
        Hex SHA-256 of the photo.
    expected : Expected

    Notes
    -----
    Report files are checked by presence and size against the manifest;
    ``findings.json`` by its hash too, so findings rewritten by a later JSON
    run do not pass with an older manifest. Checking every signature and hash
    is ``forensics verify``'s job.
    """
    doc = _read_json(folder / FINDINGS_NAME)
    if _get(doc, "evidence", "sha256") != sha256:
        return False
    if any(_get(doc, "parameters", k) != v for k, v in _normalised(expected.parameters).items()):
        return False
    if not expected.report_formats:
        return True
    if not (folder / SIGNATURE_NAME).is_file():
        return False
    manifest = _read_json(folder / MANIFEST_NAME)
    if _get(manifest, "evidence", "sha256") != sha256 or _get(manifest, "exhibit_id") != expected.exhibit_id:
        return False
    try:
        files = {f["name"]: f for f in manifest["files"]}
        wanted = [FINDINGS_NAME, *(_REPORT_FILES[f] for f in expected.report_formats)]
        if any(name not in files for name in wanted):
            return False
        if sha256_file(folder / FINDINGS_NAME) != files[FINDINGS_NAME]["sha256"]:
            return False
        return all((folder / n).stat().st_size == int(f["size"]) for n, f in files.items())
    except (KeyError, TypeError, ValueError, OSError):
        return False


def expected_parameters(detectors: list[str], detector_params: dict[str, dict[str, Any]], fusion: str,
                        case_id: str | None, examiner: str | None, reference: str | None = None) -> dict[str, Any]:
    """The subset of the findings' ``parameters`` a rerun compares (see :class:`Expected`)."""
    values = {"detectors": detectors, "detector_params": detector_params, "fusion": fusion, "case_id": case_id,
              "examiner": examiner, "reference": reference}
    return {k: values[k] for k in _COMPARED_PARAMETERS}


def _in_use(folder: Path) -> bool:
    """True when another process holds ``folder`` locked: an ``analyze`` making a bundle in it
    (:func:`forensics_core.output.staging_folder`)."""
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


def remove_temp_files(folder: Path) -> int:
    """Delete the temporary files (and folders) a killed run left directly in ``folder``; return how many.

    A folder another process holds locked is in use, not left, and stays.
    """
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return 0
    removed = 0
    for entry in entries:
        if not is_temp_name(entry.name):
            continue
        path = Path(entry.path)
        if entry.is_dir(follow_symlinks=False):
            if _in_use(path):
                continue
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)
        removed += 1
    return removed


def link_folder(out_dir: Path, name: str, target: str) -> None:
    """Make ``out_dir/name`` a relative symbolic link to ``out_dir/target``, atomically.

    An unfinished real folder of the same content at ``name`` is first renamed
    to a temporary name (the link then takes its place in one step) and
    removed.
    """
    path = out_dir / name
    if os.path.islink(path) and os.readlink(path) == target:
        return
    stale = None
    if path.is_dir() and not path.is_symlink():
        stale = Path(tempfile.mkdtemp(prefix=f".{name}.", suffix=".tmp", dir=out_dir))
        os.replace(path, stale / name)
    tmp = out_dir / f".{name}.{secrets.token_hex(4)}.tmp"
    os.symlink(target, tmp)
    try:
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    if stale is not None:
        shutil.rmtree(stale, ignore_errors=True)


class LockHeld(Exception):
    """Another batch is writing into the same output folder."""


class OutputLock:
    """An exclusive ``flock`` on ``OUT/.forensics-batch.lock`` for the whole run.

    The kernel drops it when the holder dies, even by SIGKILL; local workers
    inherit it, so it is held until the last of them is gone.
    """

    def __init__(self, out_dir: Path):
        self.path = out_dir / LOCK_NAME
        self._fd: int | None = None

    def __enter__(self) -> OutputLock:
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise LockHeld(f"another `forensics batch` is writing into {self.path.parent}") from None
        self._fd = fd
        return self

    def __exit__(self, *exc) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
