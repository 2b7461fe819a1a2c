"""The real corpus's authentic building photos, which the suites made from real photos start from.

The suites ``lens-splices`` (:mod:`.lens_splices`) and ``innocent-processing``
(:mod:`.innocent_processing`) are built on demand from the authentic photos
of the corpus's ``authentic_buildings/<set>/`` folders (a ``truth.csv`` and an
``exif.csv`` each). Those photos are for research use only: this module only
reads them, and a suite's folder holds its own photos, ``truth.csv`` and
``recipes.json``, never a copy of the corpus's.
"""

from __future__ import annotations

import csv
import hashlib
import json
from collections.abc import Collection, Sequence
from dataclasses import asdict, dataclass
from itertools import zip_longest
from pathlib import Path
from typing import TypeVar

import numpy as np
from PIL import Image

from .. import __version__
from ..analysis import environment
from .cases import TRUTH_FILE, SuiteError

RECIPES_FILE = "recipes.json"
SETS_FOLDER = "authentic_buildings"

#: OpenSfM's sample photos carry no Make or Model; all were taken with one iPhone 4S.
_UNNAMED_CAMERAS = {"opensfm_lund": "iPhone 4S", "opensfm_berlin": "iPhone 4S"}

P = TypeVar("P", bound="RealPhoto")


@dataclass(frozen=True)
class RealPhoto:
    """An authentic photo of the corpus; ``size`` is its stored grid's width and height (EXIF Orientation ignored)."""

    set: str
    file: str
    path: Path
    camera: str
    size: tuple[int, int]
    sha256: str

    @property
    def name(self) -> str:
        return f"{self.set}/{self.file}"

    @property
    def scene(self) -> str:
        """The scene this photo is in the record of ``forensics validate`` on the corpus (its set and stem), so that
        cases made from it are grouped with it when calibrators are cross-validated (:func:`..calibration.fit.scene`)."""
        return f"authentic_buildings/{self.set}:{Path(self.file).stem}"

    def describe(self) -> dict[str, object]:
        return {"set": self.set, "file": self.file, "sha256": self.sha256, "camera": self.camera,
                "size": list(self.size)}


def read_photos(corpus: Path, suite: str, skip: Collection[str] = ()) -> list[RealPhoto]:
    """The authentic photos of ``corpus/authentic_buildings/*``, but the sets named in ``skip``.

    Parameters
    ----------
    corpus : Path
        The real corpus; only read.
    suite : str
        The suite being built, named in the errors.
    skip : collection of str
        Sets left out.

    Returns
    -------
    list of RealPhoto
        In the order of the sets' names, then of their truth files.

    Raises
    ------
    SuiteError
        The corpus is absent, has no set, a photo lacks its ``exif.csv`` row or
        is not readable.
    """
    if not corpus.is_dir():
        raise SuiteError(f"the real corpus is absent ({corpus}): {suite} is built from its {SETS_FOLDER}/* photos")
    sets = sorted(p.parent for p in (corpus / SETS_FOLDER).glob(f"*/{TRUTH_FILE}") if p.parent.name not in skip)
    if not sets:
        raise SuiteError(f"{corpus}: no {SETS_FOLDER}/*/{TRUTH_FILE} to build {suite} from")
    photos = []
    for folder in sets:
        exif = {row["file"]: row for row in _rows(folder / "exif.csv")}
        for row in _rows(folder / TRUTH_FILE):
            if row["label"].strip().lower() != "authentic":
                continue
            if row["file"] not in exif:
                raise SuiteError(f"{folder / 'exif.csv'}: no row for {row['file']}")
            path = folder / row["file"]
            try:
                with Image.open(path) as img:
                    size = img.size
                with open(path, "rb") as fh:
                    digest = hashlib.file_digest(fh, "sha256").hexdigest()
            except OSError as exc:
                raise SuiteError(f"{path}: not readable as a photo ({exc})") from None
            photos.append(RealPhoto(folder.name, row["file"], path, _camera(folder.name, exif[row["file"]]), size,
                                    digest))
    return photos


def _rows(path: Path) -> list[dict[str, str]]:
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            return list(csv.DictReader(fh))
    except OSError as exc:
        raise SuiteError(f"{path}: {exc.strerror}") from None


def _camera(set_name: str, exif: dict[str, str]) -> str:
    make, model = (exif.get("make") or "").strip(), (exif.get("model") or "").strip()
    if not make and not model:
        # A set's photos without a name are taken as one camera's: its likeliest source, as for OpenSfM's.
        return _UNNAMED_CAMERAS.get(set_name, f"unknown camera of {set_name}")
    # "Canon" + "Canon EOS 1000D" is one name, as the corpus's truth files write it.
    return model if model.lower().startswith(make.lower()) else f"{make} {model}".strip()


def camera_turns(photos: Sequence[P], rng: np.random.Generator) -> list[P]:
    """``photos`` shuffled by ``rng``, then one photo of each camera before a second of any.

    The corpus holds one camera's long series beside many single photos; taken
    in turns, the first photos of a suite span as many cameras as there are.

    Parameters
    ----------
    photos : sequence of RealPhoto
        The photos to order.
    rng : numpy.random.Generator
        Draws one permutation of ``photos``.

    Returns
    -------
    list of RealPhoto
        All of ``photos``: the first of each camera, then the second, and so on.
    """
    by_camera: dict[str, list[P]] = {}
    for i in rng.permutation(len(photos)):
        by_camera.setdefault(photos[i].camera, []).append(photos[i])
    return [p for turn in zip_longest(*by_camera.values()) for p in turn if p is not None]


def downscaled(image: Image.Image, mask: Image.Image | None, factor: float) -> tuple[Image.Image, Image.Image | None]:
    """A forged photo downscaled by ``factor`` (Lanczos), and its truth mask with it.

    The mask goes bilinear, then is kept where it is half or more: on the
    pixels mostly made of the forged content.
    """
    size = (round(image.width * factor), round(image.height * factor))
    image = image.resize(size, Image.Resampling.LANCZOS)
    if mask is not None:
        mask = mask.resize(size, Image.Resampling.BILINEAR).point(lambda v: 255 if v >= 128 else 0)
    return image, mask


def save_mask(folder: Path, name: str, mask: Image.Image | None) -> str | None:
    """Write a case's truth mask as ``masks/<name>.png`` under ``folder``; its path there, or None without one."""
    if mask is None:
        return None
    mask.save(folder / f"masks/{name}.png")
    return f"masks/{name}.png"


def write_suite(folder: Path, suite: str, corpus: Path, seed: int, size: object, method: dict[str, str],
                made: Sequence[tuple[dict[str, object], dict[str, str]]],
                header: Sequence[str]) -> list[dict[str, object]]:
    """Write the ``truth.csv`` and ``recipes.json`` of a suite built into ``folder``.

    Parameters
    ----------
    folder : Path
        The suite's folder, holding its photos already.
    suite, corpus, seed
        The suite's name, the corpus it was built from and its seed, stated in ``recipes.json``.
    size : dataclass
        The suite's size, stated field by field.
    method : dict of str to str
        What the suite's builder did, in words.
    made : sequence of (dict, dict)
        Every case's recipe and ``truth.csv`` row, in the suite's order.
    header : sequence of str
        The ``truth.csv`` columns, in order; every row has them all.

    Returns
    -------
    list of dict
        The recipes, as written.
    """
    recipes = [recipe for recipe, _ in made]
    with open(folder / TRUTH_FILE, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows([row[h] for h in header] for _, row in made)
    # The same seed gives the same bytes only with the same libraries: OpenCV's remap and filters, Pillow's
    # resampling and encoder (measured: 18 of the 124 innocent-processing photos, every one made with OpenCV,
    # differed between two machines).
    document = {
        "suite": suite, "generator": f"forensics {__version__}", "packages": environment()["packages"], "seed": seed,
        "corpus": str(corpus.resolve()), "size": asdict(size), "method": method, "cases": recipes,
    }
    (folder / RECIPES_FILE).write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")
    return recipes
