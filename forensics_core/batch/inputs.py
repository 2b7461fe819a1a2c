"""The photos of a batch: found under the inputs, hashed, grouped by content.

Folders give their direct children (all descendants with ``recursive``);
hidden files and folders (name starting with ".") are left out, and so is
anything under the output folder, so a rerun never takes its own reports for
photos. Every other regular file is a photo to examine: a file that is no
image is recorded as failed with its reason, not silently passed over.
"""

from __future__ import annotations

import hashlib
import os
import stat
from collections.abc import Iterable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

_HASH_THREADS = 4
_CHUNK = 1 << 20


@dataclass(frozen=True)
class Photo:
    """One input file.

    Attributes
    ----------
    path : Path
        As given or as found under a given folder.
    sha256 : str or None
        Hex SHA-256 of the bytes, None when they could not be read.
    error : str or None
        Why the file cannot be examined (one line), else None.
    """

    path: Path
    sha256: str | None
    error: str | None = None


def _is_hidden(name: str) -> bool:
    return name.startswith(".")


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def _resolved(path: Path) -> Path:
    """``path`` resolved; made absolute only where its links loop, which resolving cannot end."""
    try:
        return path.resolve()
    except (OSError, RuntimeError):  # RuntimeError: a loop, before Python 3.13
        return Path(os.path.abspath(path))


def _is_folder(entry: os.DirEntry) -> bool:
    """Whether a folder entry is a folder; an entry that cannot be followed (a link that loops) is not."""
    try:
        return entry.is_dir()
    except OSError:
        return False


def discover(inputs: Sequence[Path], out_dir: Path, recursive: bool = False) -> list[tuple[Path, str | None]]:
    """The files under ``inputs``, each once, with the reason it cannot be used (or None).

    Files named on the command line are taken as they are, hidden or not;
    folders are listed in sorted order, without ``out_dir`` when it lies
    below them. Symbolic links to files are followed;
    links to folders are not descended into (they could loop).

    Returns
    -------
    list of (Path, str or None)
        In the order of the inputs; a missing input carries its reason.
    """
    out_resolved = out_dir.resolve()
    found: list[tuple[Path, str | None]] = []
    seen: set[Path] = set()

    def add(path: Path, reason: str | None = None) -> None:
        key = _resolved(path)
        if key not in seen:
            seen.add(key)
            found.append((path, reason))

    for item in inputs:
        if not item.is_dir():
            add(item, None if os.path.lexists(item) else "no such file or folder")
            continue
        # Only an output folder below the input folder is left out: a folder of
        # photos inside the output folder (``--out .``) is still read.
        folder = item.resolve()
        skip = out_resolved if out_resolved != folder and _inside(out_resolved, folder) else None
        for path in _folder_files(item, recursive):
            if skip is None or not _inside(_resolved(path), skip):
                add(path)
    return found


def _folder_files(folder: Path, recursive: bool) -> Iterable[Path]:
    """Every entry of the folder that is not a folder: FIFOs, devices and broken links too, so that each is
    listed as failed with its reason instead of passed over in silence."""
    if not recursive:
        try:
            names = sorted(e.name for e in os.scandir(folder) if not _is_hidden(e.name) and not _is_folder(e))
        except OSError:
            return []
        return [folder / n for n in names]
    files: list[Path] = []
    for root, dirs, names in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not _is_hidden(d))
        base = Path(root)
        files.extend(base / n for n in sorted(names) if not _is_hidden(n))
    return files


def sha256_of(path: Path) -> Photo:
    """Hash one file, or say in one line why it cannot be read (same wording as the evidence intake)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return Photo(path, None, "no such file")
    except OSError as exc:
        return Photo(path, None, f"cannot read: {exc.strerror or exc}")
    if stat.S_ISDIR(st.st_mode):
        return Photo(path, None, "is a directory, not a photo")
    if not stat.S_ISREG(st.st_mode):
        # A FIFO or device would block the read or never end.
        return Photo(path, None, "is not a regular file")
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for chunk in iter(lambda: fh.read(_CHUNK), b""):
                digest.update(chunk)
    except OSError as exc:
        return Photo(path, None, f"cannot read: {exc.strerror or exc}")
    return Photo(path, digest.hexdigest())


def hash_all(found: Sequence[tuple[Path, str | None]]) -> Iterator[Photo]:
    """Hash the discovered files a few at a time (hashlib releases the GIL; reads wait on the disk).

    Parameters
    ----------
    found : sequence of (Path, str or None)
        From :func:`discover`; entries with a reason are not read.

    Yields
    ------
    Photo
        In the order of ``found``.
    """

    def one(entry: tuple[Path, str | None]) -> Photo:
        path, reason = entry
        return Photo(path, None, reason) if reason is not None else sha256_of(path)

    with ThreadPoolExecutor(max_workers=_HASH_THREADS) as pool:
        yield from pool.map(one, found)
