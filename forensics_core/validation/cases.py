"""The photos of a validation suite and their truth.

A suite is either ``synthetic`` (every installed detector's
``synthetic_cases``, generated on the fly from a seed) or a folder
holding a truth file or the common authentic/tampered layout.

Truth file: ``truth.csv`` in the folder, UTF-8, with a header row::

    file,label,mask,jpeg_quality,kind
    photos/0001.jpg,spliced,masks/0001.png,85,copy_move
    photos/0002.jpg,authentic,,85,

``file`` is the photo's path relative to the folder; ``label`` is
``spliced`` or ``authentic`` (``tampered``, ``forged``, ``fake``, ``1`` and
``original``, ``pristine``, ``real``, ``0`` are read as the same); ``mask``
(optional) a PNG or other image of the photo's size, non-zero on manipulated
pixels. Every other column is a condition tag for the per-condition breakdown
(empty cells are left out).

Several sets can be measured in one run (:func:`read_suite`): each argument is
a set, or a parent folder whose descendant folders holding ``truth.csv`` are
the sets. Every case then carries the condition ``set``, the set's path
relative to its parent (or its folder name when named directly).

Folder layout, when there is no truth file: subfolders named (in any case)
``authentic``, ``au``, ``original``, ``pristine`` or ``real`` hold authentic
photos, and ``tampered``, ``tp``, ``spliced``, ``forged``, ``fake`` or
``manipulated`` the others, as in CASIA and Columbia; masks sit in a
``mask``, ``masks``, ``gt``, ``groundtruth`` or ``ground_truth`` folder (at the
top or inside the tampered one) and are matched by the photo's stem, with or
without a ``_gt``, ``_mask``, ``-mask`` or ``_groundtruth`` suffix.
"""

from __future__ import annotations

import csv
import hashlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image

from ..synthetic import SyntheticCase

TRUTH_FILE = "truth.csv"
SET_CONDITION = "set"
PHOTO_SUFFIXES = {".jpg", ".jpeg", ".png", ".tif", ".tiff"}
_SPLICED = {"spliced", "tampered", "forged", "fake", "manipulated", "1", "true"}
_AUTHENTIC = {"authentic", "original", "pristine", "real", "0", "false"}
_AUTH_DIRS = {"authentic", "au", "original", "pristine", "real"}
_TAMPERED_DIRS = {"tampered", "tp", "spliced", "forged", "fake", "manipulated"}
_MASK_DIRS = {"mask", "masks", "gt", "groundtruth", "ground_truth"}
_MASK_SUFFIXES = ("", "_gt", "_mask", "-mask", "_groundtruth")


class SuiteError(ValueError):
    """The suite cannot be read; the message is one line."""


@dataclass(frozen=True)
class Case:
    """One photo of a suite.

    ``mask`` is the path of the true mask image, if any; ``conditions`` the
    tags for the per-condition breakdown.
    """

    name: str
    path: Path
    spliced: bool
    mask: Path | None = None
    conditions: Mapping[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Suite:
    """The cases of one run and what identifies their set."""

    name: str
    source: str
    cases: list[Case]
    content_sha256: str


def _label(text: str, where: str) -> bool:
    value = text.strip().lower()
    if value in _SPLICED:
        return True
    if value in _AUTHENTIC:
        return False
    raise SuiteError(f"{where}: label {text!r} is neither spliced nor authentic")


def _inside(root: Path, rel: str, where: str) -> Path:
    if "\0" in rel:
        raise SuiteError(f"{where}: {rel!r} holds a NUL byte, which no file name can")
    path = (root / rel).resolve()
    if not path.is_relative_to(root.resolve()):
        raise SuiteError(f"{where}: {rel!r} points outside the suite folder")
    if not path.is_file():
        raise SuiteError(f"{where}: no file {rel!r}")
    return path


def read_truth_file(root: Path) -> list[Case]:
    """Cases listed in ``root/truth.csv`` (format in this module's docstring)."""
    try:
        return _truth_cases(root)
    except UnicodeDecodeError:
        raise SuiteError(f"{root / TRUTH_FILE}: not UTF-8 text") from None
    except csv.Error as exc:
        raise SuiteError(f"{root / TRUTH_FILE}: not readable as CSV ({exc})") from None


def _truth_cases(root: Path) -> list[Case]:
    cases = []
    with open(root / TRUTH_FILE, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        if reader.fieldnames is None or not {"file", "label"} <= set(reader.fieldnames):
            raise SuiteError(f"{root / TRUTH_FILE}: the header must name at least the columns file and label")
        for line, row in enumerate(reader, start=2):
            where = f"{TRUTH_FILE} line {line}"
            path = _inside(root, row["file"], where)
            mask = _inside(root, row["mask"], where) if (row.get("mask") or "").strip() else None
            tags = {k: v.strip() for k, v in row.items() if k not in ("file", "label", "mask") and k and (v or "").strip()}
            cases.append(Case(Path(row["file"]).with_suffix("").as_posix().replace("/", "_"), path,
                              _label(row["label"], where), mask, tags))
    return cases


def _photos(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file() and p.suffix.lower() in PHOTO_SUFFIXES
                  and not ({d.lower() for d in p.relative_to(folder).parts[:-1]} & _MASK_DIRS))


def read_layout(root: Path) -> list[Case]:
    """Cases of a folder with authentic/ and tampered/ subfolders (this module's docstring)."""
    subdirs = {d.name.lower(): d for d in root.iterdir() if d.is_dir()}
    auth = [d for n, d in subdirs.items() if n in _AUTH_DIRS]
    tamp = [d for n, d in subdirs.items() if n in _TAMPERED_DIRS]
    if not auth or not tamp:
        raise SuiteError(f"{root}: no {TRUTH_FILE} and no authentic/ and tampered/ subfolders")
    mask_dirs = [d for n, d in subdirs.items() if n in _MASK_DIRS]
    mask_dirs += [m for t in tamp for m in t.iterdir() if m.is_dir() and m.name.lower() in _MASK_DIRS]
    masks = {p.stem.lower(): p for d in mask_dirs for p in sorted(d.rglob("*")) if p.is_file()}

    def mask_for(photo: Path) -> Path | None:
        return next((masks[photo.stem.lower() + s] for s in _MASK_SUFFIXES if photo.stem.lower() + s in masks), None)

    cases = [Case(f"au_{p.stem}", p, False) for d in auth for p in _photos(d)]
    cases += [Case(f"tp_{p.stem}", p, True, mask_for(p)) for d in tamp for p in _photos(d)]
    return cases


def _file_sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def content_hash(cases: Sequence[Case]) -> str:
    """SHA-256 over every photo's and mask's bytes and its label: names the exact set measured."""
    lines = sorted(
        f"{_file_sha256(c.path)} {int(c.spliced)} {_file_sha256(c.mask) if c.mask else '-'} "
        + ",".join(f"{k}={v}" for k, v in sorted(c.conditions.items()))
        for c in cases
    )
    return hashlib.sha256("\n".join(lines).encode()).hexdigest()


def _set_cases(root: Path) -> list[Case]:
    cases = read_truth_file(root) if (root / TRUTH_FILE).is_file() else read_layout(root)
    if not cases:
        raise SuiteError(f"{root}: no photos found")
    return cases


def _unique(cases: list[Case]) -> list[Case]:
    names = [c.name for c in cases]
    if len(set(names)) == len(names):
        return cases
    return [Case(f"{i:05d}_{c.name}", c.path, c.spliced, c.mask, c.conditions) for i, c in enumerate(cases)]


def folder_suite(root: Path) -> Suite:
    """A suite read from a folder with ``truth.csv`` or the authentic/tampered layout."""
    if not root.is_dir():
        raise SuiteError(f"{root}: not a folder (and not the name of a built-in suite)")
    cases = _unique(_set_cases(root))
    return Suite(root.name, str(root.resolve()), cases, content_hash(cases))


def _is_set(folder: Path) -> bool:
    if (folder / TRUTH_FILE).is_file():
        return True
    names = {d.name.lower() for d in folder.iterdir() if d.is_dir()}
    return bool(names & _AUTH_DIRS) and bool(names & _TAMPERED_DIRS)


def find_sets(root: Path) -> list[tuple[str, Path]]:
    """The sets ``root`` names, as ``(set name, folder)``: itself, or every descendant folder holding a truth file.

    A set inside another set belongs to the outer one and is not a set of its own.
    """
    if not root.is_dir():
        raise SuiteError(f"{root}: not a folder (and not the name of a built-in suite)")
    if _is_set(root):
        return [(root.name, root)]
    found = sorted(p.parent for p in root.rglob(TRUTH_FILE) if p.is_file())
    outermost = [f for f in found if not any(o != f and f.is_relative_to(o) for o in found)]
    if not outermost:
        raise SuiteError(f"{root}: no {TRUTH_FILE} and no authentic/ and tampered/ subfolders, nor any set below it")
    return [(f.relative_to(root).as_posix(), f) for f in outermost]


def read_suite(roots: Sequence[Path]) -> Suite:
    """One suite of every set named by ``roots`` (see :func:`find_sets`), each case tagged with its ``set``.

    With more than one set, case names are prefixed with their set's so that
    they stay unique.
    """
    sets = [s for root in roots for s in find_sets(root)]
    if len({name for name, _ in sets}) != len(sets):
        sets = [(folder.resolve().as_posix(), folder) for _, folder in sets]
    cases = []
    for name, folder in sets:
        prefix = f"{name.replace('/', '_')}__" if len(sets) > 1 else ""
        cases += [Case(prefix + c.name, c.path, c.spliced, c.mask, {**c.conditions, SET_CONDITION: name})
                  for c in _set_cases(folder)]
    cases = _unique(cases)
    name = " + ".join(root.name for root in roots)
    return Suite(name, "; ".join(str(root.resolve()) for root in roots), cases, content_hash(cases))


def write_synthetic(generated: Iterable[tuple[str, SyntheticCase]], folder: Path) -> list[Case]:
    """Write plugins' synthetic cases as files (photo, and mask as PNG) under ``folder``.

    ``generated`` yields ``(plugin name, case)``; the plugin name prefixes
    each case's name and becomes the ``generator`` condition.
    """
    folder.mkdir(parents=True, exist_ok=True)
    cases = []
    for plugin, sc in generated:
        name = f"{plugin}-{sc.name}"
        path = folder / f"{name}{sc.suffix}"
        path.write_bytes(sc.data)
        mask_path = None
        if sc.mask is not None:
            mask_path = folder / f"{name}.mask.png"
            Image.fromarray(np.asarray(sc.mask, dtype=bool).astype(np.uint8) * 255).save(mask_path)
        cases.append(Case(name, path, sc.spliced, mask_path, {**dict(sc.conditions), "generator": plugin}))
    return cases


def load_mask(path: Path, shape: tuple[int, int]) -> np.ndarray | None:
    """A true mask as a boolean ``(H, W)`` array, or None when its size differs from the photo's."""
    with Image.open(path) as img:
        arr = np.asarray(img.convert("L")) > 0
    return arr if arr.shape == tuple(shape) else None
