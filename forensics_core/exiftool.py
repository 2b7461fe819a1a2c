"""Metadata as ExifTool reads it: EXIF, MakerNotes, XMP, IPTC, ICC, JUMBF, grouped by ExifTool's family-1 groups.

ExifTool (Phil Harvey; Debian ``libimage-exiftool-perl``) is the reader
examiners cite. It runs as a subprocess with an argument list (never a
shell), reads the evidence bytes from its standard input (never the path, so
what it reads is what was hashed), and is stopped after a time limit. When it
is absent, fails or times out, the caller falls back to Pillow's EXIF and
says so.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from dataclasses import dataclass
from functools import lru_cache

ARGUMENTS = ("-json", "-G1", "-a", "-u", "-n")
# Groups that describe ExifTool's own run or the standard-input pseudo-file,
# not the evidence.
_SKIPPED_GROUPS = frozenset({"ExifTool", "System"})
MAX_TAGS = 5000


@dataclass(frozen=True)
class ExifToolTag:
    """One tag as ExifTool reports it, its value already rendered as safe text by the caller."""

    group: str
    name: str
    value: object


@dataclass(frozen=True)
class ExifToolResult:
    """ExifTool's reading of one file: its tags, or why there are none.

    Attributes
    ----------
    version : str or None
        ExifTool's version, None when it is not installed.
    tags : list of ExifToolTag
        In ExifTool's order, at most :data:`MAX_TAGS`.
    error : str or None
        One line saying why ExifTool gave nothing (absent, timed out, failed).
    """

    version: str | None
    tags: list[ExifToolTag]
    error: str | None = None


@lru_cache(maxsize=1)
def version() -> str | None:
    """ExifTool's version string, or None when ``exiftool`` is not on the PATH or does not answer."""
    exe = shutil.which("exiftool")
    if exe is None:
        return None
    try:
        done = subprocess.run([exe, "-ver"], capture_output=True, timeout=30, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    text = done.stdout.decode("ascii", "replace").strip()
    return text if done.returncode == 0 and text else None


def read(data: bytes, timeout_s: float = 30.0) -> ExifToolResult:
    """Every tag ExifTool finds in ``data``.

    Parameters
    ----------
    data : bytes
        The evidence file's bytes.
    timeout_s : float
        ExifTool is killed after this many seconds.

    Returns
    -------
    ExifToolResult
        With ``error`` set (and no tags) when ExifTool is absent, fails, times
        out or prints something that is not its JSON.
    """
    found = version()
    exe = shutil.which("exiftool")
    if found is None or exe is None:
        return ExifToolResult(None, [], "ExifTool is not installed")
    try:
        done = subprocess.run([exe, *ARGUMENTS, "-"], input=data, capture_output=True, timeout=timeout_s,
                              check=False)
    except subprocess.TimeoutExpired:
        return ExifToolResult(found, [], f"ExifTool did not finish within {timeout_s:g} s")
    except OSError as exc:
        return ExifToolResult(found, [], f"ExifTool could not be run: {exc.strerror or exc}")
    try:
        parsed = json.loads(done.stdout.decode("utf-8", "replace"))
        record = parsed[0] if isinstance(parsed, list) and parsed and isinstance(parsed[0], dict) else None
    except (ValueError, RecursionError):
        record = None
    if record is None:
        first = done.stderr.decode("utf-8", "replace").strip().splitlines()[:1]
        return ExifToolResult(found, [], f"ExifTool read nothing (exit {done.returncode}"
                                         f"{': ' + first[0][:200] if first else ''})")
    tags = []
    for key, value in record.items():
        group, _, name = key.partition(":")
        if not name or group in _SKIPPED_GROUPS:
            continue
        tags.append(ExifToolTag(group, name, value))
        if len(tags) >= MAX_TAGS:
            break
    return ExifToolResult(found, tags)
