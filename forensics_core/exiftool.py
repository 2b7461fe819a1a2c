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
    return start(data).result(timeout_s)


def start(data: bytes) -> Reading:
    """Start ExifTool on ``data`` and return at once; :meth:`Reading.result` waits for its tags.

    ExifTool spends most of its time starting Perl, which runs on another core
    while the caller decodes the photo.
    """
    exe = shutil.which("exiftool")
    if exe is None:
        return Reading(None, data, "ExifTool is not installed")
    try:
        process = subprocess.Popen([exe, *ARGUMENTS, "-"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE)
    except OSError as exc:
        return Reading(None, data, f"ExifTool could not be run: {exc.strerror or exc}")
    return Reading(process, data, None)


class Reading:
    """An ExifTool run under way (or one that could not start); call :meth:`result` or :meth:`cancel` once."""

    def __init__(self, process: subprocess.Popen[bytes] | None, data: bytes, error: str | None) -> None:
        self._process, self._data, self._error = process, data, error

    def cancel(self) -> None:
        """Stop the run without reading it (the intake refused the photo)."""
        if self._process is not None:
            self._process.kill()
            self._process.communicate()
            self._process = None

    def result(self, timeout_s: float = 30.0) -> ExifToolResult:
        """The tags, after sending the bytes and waiting at most ``timeout_s`` seconds."""
        process, self._process = self._process, None
        if process is None:
            return ExifToolResult(None, [], self._error or "ExifTool was not run")
        try:
            stdout, stderr = process.communicate(self._data, timeout=timeout_s)
        except subprocess.TimeoutExpired:
            process.kill()
            process.communicate()
            return ExifToolResult(None, [], f"ExifTool did not finish within {timeout_s:g} s")
        return _parsed(stdout, stderr, process.returncode)


def _parsed(stdout: bytes, stderr: bytes, returncode: int) -> ExifToolResult:
    """ExifTool's JSON output as tags, or why it is not."""
    try:
        parsed = json.loads(stdout.decode("utf-8", "replace"))
        record = parsed[0] if isinstance(parsed, list) and parsed and isinstance(parsed[0], dict) else None
    except (ValueError, RecursionError):
        record = None
    if record is None:
        first = stderr.decode("utf-8", "replace").strip().splitlines()[:1]
        return ExifToolResult(None, [], f"ExifTool read nothing (exit {returncode}"
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
    stated = _VERSION.search(stdout)
    return ExifToolResult(stated.group(1).decode("ascii") if stated else "of unstated version", tags)
