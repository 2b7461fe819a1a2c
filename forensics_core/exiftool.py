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
import re
import shutil
import subprocess
from dataclasses import dataclass

ARGUMENTS = ("-json", "-G1", "-a", "-u", "-n")
_VERSION = re.compile(rb'"ExifTool:ExifToolVersion":\s*"?([0-9][0-9.]*)')
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
        ExifTool's version as it states it, None when it gave no reading.
    tags : list of ExifToolTag
        In ExifTool's order, at most :data:`MAX_TAGS`.
    error : str or None
        One line saying why ExifTool gave nothing (absent, timed out, failed).
    """

    version: str | None
    tags: list[ExifToolTag]
    error: str | None = None


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
    exe = shutil.which("exiftool")
    if exe is None:
        return ExifToolResult(None, [], "ExifTool is not installed")
    try:
        done = subprocess.run([exe, *ARGUMENTS, "-"], input=data, capture_output=True, timeout=timeout_s,
                              check=False)
    except subprocess.TimeoutExpired:
        return ExifToolResult(None, [], f"ExifTool did not finish within {timeout_s:g} s")
    except OSError as exc:
        return ExifToolResult(None, [], f"ExifTool could not be run: {exc.strerror or exc}")
    try:
        parsed = json.loads(done.stdout.decode("utf-8", "replace"))
        record = parsed[0] if isinstance(parsed, list) and parsed and isinstance(parsed[0], dict) else None
    except (ValueError, RecursionError):
        record = None
    if record is None:
        first = done.stderr.decode("utf-8", "replace").strip().splitlines()[:1]
        return ExifToolResult(None, [], f"ExifTool read nothing (exit {done.returncode}"
                                         f"{': ' + first[0][:200] if first else ''})")
    tags = []
    for key, value in record.items():
        group, _, name = key.partition(":")
        if not name or group in _SKIPPED_GROUPS:
            continue
        tags.append(ExifToolTag(group, name, value))
        if len(tags) >= MAX_TAGS:
            break
    # The version as ExifTool printed it (12.60 stays 12.60), read from the
    # same output rather than from a second run of ``exiftool -ver``.
    stated = _VERSION.search(done.stdout)
    return ExifToolResult(stated.group(1).decode("ascii") if stated else "of unstated version", tags)
