"""Which folder each photo gets, which photos need work, and which are duplicates.

Naming follows ``analyze``: ``OUT/<stem>``, or ``OUT/<stem>-<first 12 hex of
SHA-256>`` when stems clash. Unlike ``analyze`` the choice does not depend on
processing order, so a rerun finds the same folders:

* photos are taken in sorted path order, stems compared without case (two
  folders differing only in case are one folder on some file systems);
* within a clash, the plain ``<stem>`` goes to the photo whose outputs are
  already there (from an earlier run), else to the first photo if the folder
  is free; the others get the hash suffix. A folder holding another photo's
  outputs or anything else is never written into.

Photos with the same bytes are analysed once. The first of them (whose
folder is already finished, if any) is the primary; the others' folders are
relative symbolic links to the primary's folder (a duplicate with the same
stem shares the folder itself), and the summary records whose duplicate each
one is.
"""

from __future__ import annotations

import os
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from .inputs import Photo
from .resume import LOCK_NAME, Expected, is_complete, is_temp_name, recorded_sha

SUMMARY_JSON = "summary.json"
SUMMARY_CSV = "summary.csv"
INDEX_HTML = "index.html"
_RESERVED = {".", "..", SUMMARY_JSON, SUMMARY_CSV, INDEX_HTML, LOCK_NAME}


@dataclass
class Entry:
    """One output folder: the photos of one stem and one content.

    Attributes
    ----------
    stem : str
        Stem of the first photo (sorted by path).
    sha256 : str
    paths : list of Path
        The photos, sorted.
    name : str
        The folder's name under the output folder.
    complete : bool
        Its outputs were finished by an earlier run with the same settings.
    """

    stem: str
    sha256: str
    paths: list[Path] = field(default_factory=list)
    name: str = ""
    complete: bool = False


@dataclass(frozen=True)
class Job:
    """One photo to analyse, as shipped to a worker (plain strings: it may cross the network)."""

    path: str
    sha256: str
    folder: str


@dataclass
class Group:
    """All photos of one content: the primary entry and the entries that duplicate it."""

    sha256: str
    primary: Entry
    others: list[Entry]
    needs_run: bool


@dataclass
class Plan:
    """The batch's work, fixed before any photo is analysed.

    Attributes
    ----------
    out_dir : Path
    photos : list of Photo
        Every input, in discovery order (the summary's rows).
    groups : dict of str to Group
        By SHA-256.
    entry_of : dict of Path to Entry
        The output folder of each readable photo.
    """

    out_dir: Path
    photos: list[Photo]
    groups: dict[str, Group]
    entry_of: dict[Path, Entry]

    def folder(self, entry: Entry) -> Path:
        return self.out_dir / entry.name

    def primary_path(self, sha256: str) -> Path:
        return self.groups[sha256].primary.paths[0]

    def jobs(self) -> list[Job]:
        """The primaries not finished yet, in sorted path order."""
        return [Job(str(g.primary.paths[0]), g.sha256, str(self.folder(g.primary)))
                for g in self.groups.values() if g.needs_run]


def _reserved(stem: str) -> bool:
    return stem.casefold() in _RESERVED or is_temp_name(stem)


def _assign_names(entries: Sequence[Entry], out_dir: Path) -> None:
    by_stem: dict[str, list[Entry]] = defaultdict(list)
    for entry in entries:
        by_stem[entry.stem.casefold()].append(entry)
    for group in by_stem.values():
        winner = None
        if not _reserved(group[0].stem):
            winner = next((e for e in group if recorded_sha(out_dir / e.stem) == e.sha256), None)
            if winner is None and recorded_sha(out_dir / group[0].stem) is None:
                winner = group[0]
        for entry in group:
            entry.name = entry.stem if entry is winner else f"{entry.stem}-{entry.sha256[:12]}"


def make_plan(photos: Sequence[Photo], out_dir: Path, expected: Expected, force: bool = False) -> Plan:
    """Name every photo's folder, find the finished ones and the duplicates.

    Parameters
    ----------
    photos : sequence of Photo
        Hashed inputs, in discovery order.
    out_dir : Path
    expected : Expected
        What a finished folder must show to be kept.
    force : bool
        Redo every photo, finished or not.
    """
    readable = sorted((p for p in photos if p.error is None), key=lambda p: str(p.path))
    entries: dict[tuple[str, str], Entry] = {}
    entry_of: dict[Path, Entry] = {}
    for photo in readable:
        stem = photo.path.stem or "photo"
        entry = entries.setdefault((stem.casefold(), photo.sha256), Entry(stem, photo.sha256))
        entry.paths.append(photo.path)
        entry_of[photo.path] = entry
    _assign_names(list(entries.values()), out_dir)

    by_sha: dict[str, list[Entry]] = defaultdict(list)
    for entry in entries.values():
        by_sha[entry.sha256].append(entry)
    groups: dict[str, Group] = {}
    for sha, group in by_sha.items():
        group.sort(key=lambda e: str(e.paths[0]))
        for entry in group:
            entry.complete = not force and is_complete(out_dir / entry.name, sha, expected)
        real = [e for e in group if not os.path.islink(out_dir / e.name)]
        primary = (next((e for e in real if e.complete), None) or next((e for e in group if e.complete), None)
                   or (real or group)[0])
        groups[sha] = Group(sha, primary, [e for e in group if e is not primary], not primary.complete)
    return Plan(out_dir, list(photos), groups, entry_of)
