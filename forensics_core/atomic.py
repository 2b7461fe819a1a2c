"""Atomic file writing: a file is either its old version or its new one, never half of one."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def _write_beside(path: Path, data: bytes) -> str:
    """Write ``data``, synced, to a new temporary file (mode 0600) beside ``path``; return its name."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return tmp


def write_atomic(path: Path, data: bytes) -> Path:
    """Write ``data`` to a temporary file beside ``path``, then rename it into place.

    A run stopped at any moment leaves either the old file or the new one,
    never half of one.
    """
    tmp = _write_beside(path, data)
    try:
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_new(path: Path, data: bytes) -> Path:
    """Write ``data`` to ``path``, which must not exist: :class:`FileExistsError` otherwise.

    Of processes writing the same new path at once exactly one succeeds, and
    no reader sees half a file: the data is written whole beside ``path`` and
    then hard-linked to it, since a link, unlike a rename, fails when the name
    is taken. The file has mode 0600.
    """
    tmp = _write_beside(path, data)
    try:
        os.link(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)
    return path
