"""Case material beside the evidence: reference photos of the camera that allegedly took it.

``forensics analyze PHOTO --reference DIR`` takes in every file of ``DIR``
as it takes in the evidence (:func:`~forensics_core.evidence.load_evidence`:
bytes hashed before decoding, never written), lists each in the findings
(``references``) and the report, and passes the set to the detectors whose
spec declares ``uses_reference`` (``Detector.analyze(..., reference=...)``).
A detector that needs it is recorded ``skipped`` without it.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterator
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from .evidence import Evidence, EvidenceError, load_evidence
from .findings import ReferenceRecord


class ReferenceError(EvidenceError):
    """The reference folder cannot serve: missing, empty, or holding a file that is no readable photo."""


@dataclass(frozen=True)
class ReferenceSet:
    """Reference photos of one claimed camera, taken in read-only.

    Attributes
    ----------
    directory : str
        The folder as given.
    photos : tuple of Evidence
        Each file, taken in as evidence is (hashes first), in name order.
    """

    directory: str
    photos: tuple[Evidence, ...]

    @property
    def records(self) -> list[ReferenceRecord]:
        """What the findings list of each photo: name, size, hash, format and pixel size."""
        return [ReferenceRecord(name=p.info.name, size=p.info.size, sha256=p.info.sha256, format=p.info.format,
                                width=p.info.width, height=p.info.height) for p in self.photos]

    @property
    def digest(self) -> str:
        """SHA-256 of the photos' SHA-256s in name order: one name for this set of references (a cache key)."""
        return hashlib.sha256("\n".join(p.info.sha256 for p in self.photos).encode()).hexdigest()

    def __iter__(self) -> Iterator[Evidence]:
        return iter(self.photos)

    def __len__(self) -> int:
        return len(self.photos)


def load_references(directory: str | os.PathLike[str], *, max_pixels: int) -> ReferenceSet:
    """Take in every file of ``directory`` (not its sub-folders; hidden files left out) as a reference photo.

    Raises
    ------
    ReferenceError
        With a one-line reason: the folder is missing, is no folder, holds no
        file, or one of its files cannot be taken in (that file's reason).
    """
    folder = Path(directory)
    if not folder.is_dir():
        raise ReferenceError(f"{folder}: {'not a folder' if folder.exists() else 'no such folder'}")
    files = sorted(p for p in folder.iterdir() if p.is_file() and not p.name.startswith("."))
    if not files:
        raise ReferenceError(f"{folder}: no reference photo in the folder")
    photos = []
    for path in files:
        try:
            photos.append(load_evidence(path, max_pixels=max_pixels))
        except EvidenceError as exc:
            raise ReferenceError(f"reference {path}: {exc}") from None
    return ReferenceSet(str(directory), tuple(photos))


@lru_cache(maxsize=2)
def references_for(directory: str, max_pixels: int) -> ReferenceSet:
    """:func:`load_references`, once per process for a run's photos."""
    return load_references(directory, max_pixels=max_pixels)
