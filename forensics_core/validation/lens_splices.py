"""Real splices for the lens-distortion test: the suite ``forensics validate lens-splices``.

Chennamma and Rangarajan [1]_ detect splices from lens radial distortion: a
straight 3-D line is imaged bowed by the lens' k1, by an amount that grows
with its distance from the image centre, so the lines of a piece pasted from
another camera's photo, moved to another distance from the centre or
rescaled bow in a way that disagrees with the rest of the photo. This module
forges those three kinds from the authentic photos of the real corpus's
``authentic_buildings/*`` sets (default ``../shared/data/real``). Those photos
are for research use only, so they are only read, and the suite is built on
demand into a folder outside the repository, never committed:

``other_camera``
    a rectangle of a photo from another camera, the donor first resized as a
    whole so that its larger side matches the host's, pasted into a corner
    of the host at a distance from the centre other than its own;
``moved``
    a rectangle of the host pasted where its distance from the centre
    differs from its own by at least a quarter of the half-diagonal;
``rescaled``
    a rectangle of the host rescaled by 0.7-0.85 or 1.2-1.4 and pasted elsewhere;
``control``
    the host with nothing pasted, one per host.

Each rectangle is placed where the long straight edges (LSD segments at
least 15 % of the host's shorter side) inside it add up longest, since a piece
without lines gives the test nothing to measure. A host's cases and its
control are saved alike, as a forger's export would be: one JPEG quality from
{85, 90, 92, 95, 98} and, for about a quarter of the hosts, the whole photo
downscaled by 0.6-0.8, without EXIF. So a control differs from its host's
forgeries by the paste alone. Photos are taken on their stored pixel grid,
EXIF Orientation ignored, as the detectors read them.

The suite folder holds the photos (``*.jpg``), ``masks/*.png``,
``truth.csv`` (read by :mod:`.cases`; conditions ``kind``, ``jpeg_quality``,
``resized``, ``host``, ``donor``, ``two_directions``) and ``recipes.json``:
every case's recipe, with the host's and donor's SHA-256, the rectangles, the
scale, the export and the case's own seed. The same corpus and seed give the
same files.

References
----------
.. [1] K. S. Chennamma and L. Rangarajan, "Image splicing detection using
   inherent lens radial distortion", International Journal of Computer
   Science Issues 7(6) (2010) 149-158.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from PIL import Image

from .cases import Suite, SuiteError, folder_suite
from .real_corpus import RealPhoto, camera_turns, downscaled, read_photos, save_mask, write_suite

LENS_SPLICES = "lens-splices"
OTHER_CAMERA, MOVED, RESCALED, CONTROL = "other_camera", "moved", "rescaled", "control"
_QUALITIES = (85, 90, 92, 95, 98)
_RESIZED_SHARE = 0.25
_RESIZE_RANGE = (0.6, 0.8)
_SUBSAMPLING = "4:2:0"
_REGION_SHARE = (0.20, 0.35)
_MIN_REGION_PX = 300
#: On small photos 300 px would be most of the frame; a piece stays below this share of the shorter side.
_MAX_REGION_SHARE = 0.4
_ASPECT_RANGE = (0.75, 4 / 3)
_LONG_EDGE_SHARE = 0.15
#: Shorter segments are long in no frame they can be pasted into (for hosts up to three times as long as high).
_KEPT_EDGE_SHARE = 0.05
_TWO_DIRECTIONS_DEG = 30.0
_MIN_DISTANCE_CHANGE = 0.25
_SCALE_RANGES = ((0.7, 0.85), (1.2, 1.4))
_CORNER_INSET_SHARE = 0.04
#: LSD runs on a copy of at most this side: long edges survive, and a 16 MP photo takes 0.1 s, not 2 s.
_LSD_SIDE = 1024
_HEADER = ("file", "label", "mask", "kind", "jpeg_quality", "resized", "host", "donor", "two_directions")

Box = tuple[int, int, int, int]
"""A rectangle as x, y (top left), width, height in pixels."""


@dataclass(frozen=True)
class SuiteSize:
    """How many forgeries of each kind, and over how many hosts; every host used also gets one control."""

    other_camera: int = 40
    moved: int = 30
    rescaled: int = 20
    hosts: int = 40


@dataclass(frozen=True, eq=False)
class CorpusPhoto(RealPhoto):
    """An authentic photo of the corpus with ``segments``: its LSD segments at least 5 % of its shorter side.

    ``segments`` has shape ``(N, 4)``, as x0, y0, x1, y1 in the stored grid's pixels.
    """

    segments: np.ndarray


@dataclass(frozen=True)
class Export:
    """How a forger saved the photo: JPEG quality and the whole photo's downscale factor, if any."""

    quality: int
    resize: float | None


@dataclass(frozen=True)
class Plan:
    """One case before it is made; ``seed`` drives its own draws (None for a control, which draws nothing)."""

    name: str
    kind: str
    host: CorpusPhoto
    donor: CorpusPhoto | None
    export: Export
    seed: int | None


@dataclass(frozen=True)
class Region:
    """A rectangle and the long straight edges inside it."""

    box: Box
    edge_length: float
    edges: int
    two_directions: bool


@dataclass(frozen=True)
class Paste:
    """Where a piece came from and went: ``source`` in the donor's frame (resized to ``donor_size``) or the host's.

    ``distances`` are the source's and the destination's centre distances from
    their frame's centre, as shares of its half-diagonal.
    """

    source: Region
    destination: Box
    scale: float | None
    donor_size: tuple[int, int] | None
    distances: tuple[float, float]


def build_lens_splices(corpus: Path, folder: Path, seed: int, size: SuiteSize = SuiteSize()) -> list[dict[str, object]]:
    """Forge the suite from ``corpus`` into ``folder`` (see this module's docstring).

    Parameters
    ----------
    corpus : Path
        The real corpus, holding ``authentic_buildings/<set>/truth.csv`` and
        ``exif.csv``; only read.
    folder : Path
        Where the photos, ``masks/``, ``truth.csv`` and ``recipes.json`` are
        written (created if needed; files of the same names are replaced).
    seed : int
        Chooses hosts, donors, kinds, rectangles, scales and exports.
    size : SuiteSize
        Forgeries per kind and hosts; fewer hosts when the corpus has fewer
        photos with long edges.

    Returns
    -------
    list of dict
        Every case's recipe, as written to ``recipes.json``.

    Raises
    ------
    SuiteError
        The corpus is absent, has no usable photo, or has a single camera
        while ``other_camera`` cases are asked for.
    """
    photos = read_corpus(corpus)
    plans = _plan(photos, seed, size)
    (folder / "masks").mkdir(parents=True, exist_ok=True)
    made = []
    for host in dict.fromkeys(p.host for p in plans):
        # Each host is decoded once for all its cases and its control.
        with Image.open(host.path) as img:
            pixels = np.asarray(img.convert("RGB"))
        made += [_make(plan, pixels, folder) for plan in plans if plan.host is host]
    order = {p.name: i for i, p in enumerate(plans)}
    made.sort(key=lambda m: order[m[0]["name"]])
    method = {
        "regions": f"LSD on the luma (copy of at most {_LSD_SIDE} px), rectangle maximising the length of "
                   f"segments inside it at least {_LONG_EDGE_SHARE:.0%} of the host's shorter side",
        "two_directions": f"long segments inside whose directions differ by more than {_TWO_DIRECTIONS_DEG:g} degrees",
        "pixel_grid": "stored, EXIF Orientation ignored",
        "resampling": "Pillow LANCZOS (donor, rescaled piece, whole-photo downscale); masks bilinear, >= 50 %",
        "export": f"Pillow JPEG, subsampling {_SUBSAMPLING}, no EXIF, ICC or XMP written",
    }
    return write_suite(folder, LENS_SPLICES, corpus, seed, size, method, made, _HEADER)


def lens_splices_suite(corpus: Path, folder: Path, seed: int, size: SuiteSize = SuiteSize()) -> Suite:
    """Build the suite into ``folder`` (:func:`build_lens_splices`) and read it as a folder suite."""
    build_lens_splices(corpus, folder, seed, size)
    return replace(folder_suite(folder), name=LENS_SPLICES, source=f"{corpus.resolve()} (seed {seed})")


def read_corpus(corpus: Path) -> list[CorpusPhoto]:
    """The authentic photos of ``corpus/authentic_buildings/*``, with camera, size and LSD segments."""
    photos = []
    for photo in read_photos(corpus, LENS_SPLICES):
        try:
            segments = _segments(photo)
        except OSError as exc:
            raise SuiteError(f"{photo.path}: not readable as a photo ({exc})") from None
        photos.append(CorpusPhoto(**vars(photo), segments=segments))
    return photos


def _segments(photo: RealPhoto) -> np.ndarray:
    """The photo's LSD segments at least 5 % of its shorter side, in its stored grid's pixels."""
    import cv2

    size = photo.size
    with Image.open(photo.path) as img:
        # JPEG's DCT scaling decodes a reduced copy directly, several times faster than decoding the whole.
        img.draft("L", (_LSD_SIDE, _LSD_SIDE))
        luma = np.asarray(img.convert("L"))
    factor = _LSD_SIDE / max(luma.shape)
    if factor < 1:
        luma = cv2.resize(luma, (round(luma.shape[1] * factor), round(luma.shape[0] * factor)),
                          interpolation=cv2.INTER_AREA)
    found = cv2.createLineSegmentDetector().detect(luma)[0]
    segments = np.zeros((0, 4)) if found is None else found.reshape(-1, 4).astype(float)
    scale = np.array([size[0] / luma.shape[1], size[1] / luma.shape[0]] * 2)
    segments = (segments + 0.5) * scale - 0.5
    lengths = np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
    return segments[lengths >= _KEPT_EDGE_SHARE * min(size)]


def _has_long_edges(photo: CorpusPhoto) -> bool:
    lengths = np.hypot(*(photo.segments[:, 2:] - photo.segments[:, :2]).T)
    return bool((lengths >= _LONG_EDGE_SHARE * min(photo.size)).any())


def _plan(photos: list[CorpusPhoto], seed: int, size: SuiteSize) -> list[Plan]:
    """Hosts, donors, exports and case seeds: every draw of the suite that precedes the pixels."""
    usable = [p for p in photos if _has_long_edges(p)]
    if not usable:
        raise SuiteError(f"no photo of the corpus holds a straight edge {_LONG_EDGE_SHARE:.0%} of its shorter side long")
    cameras = sorted({p.camera for p in usable})
    if size.other_camera and len(cameras) < 2:
        raise SuiteError(f"{OTHER_CAMERA} cases need photos of two cameras; the corpus has only {cameras[0]}")
    rng = np.random.default_rng(seed)
    # One photo of each camera before a second of any: one camera's 32 photos would otherwise fill the hosts.
    hosts = camera_turns(usable, rng)[:size.hosts]
    exports = {}
    for host in hosts:
        quality = int(rng.choice(_QUALITIES))
        exports[host.name] = Export(quality, round(float(rng.uniform(*_RESIZE_RANGE)), 3)
                                    if rng.random() < _RESIZED_SHARE else None)
    plans = []
    for kind, count in ((OTHER_CAMERA, size.other_camera), (MOVED, size.moved), (RESCALED, size.rescaled)):
        order = rng.permutation(len(hosts))
        for i in range(count):
            host = hosts[order[i % len(hosts)]]
            donor = None
            if kind == OTHER_CAMERA:
                # A camera first, then its photo: the cameras with many photos would otherwise give most pieces.
                others = [c for c in cameras if c != host.camera]
                camera = others[rng.integers(len(others))]
                pool = [p for p in usable if p.camera == camera]
                donor = pool[rng.integers(len(pool))]
            plans.append(Plan(f"{kind}_{i + 1:03d}", kind, host, donor, exports[host.name], int(rng.integers(2**31))))
    plans += [Plan(f"{CONTROL}_{i + 1:03d}", CONTROL, h, None, exports[h.name], None) for i, h in enumerate(hosts)]
    return plans


def _piece_size(rng: np.random.Generator, frame: tuple[int, int]) -> tuple[int, int]:
    """A rectangle's width and height for ``frame``: 20-35 % of its shorter side, 300 px where the photo allows."""
    short = min(frame)
    side = max(rng.uniform(*_REGION_SHARE) * short, min(_MIN_REGION_PX, _MAX_REGION_SHARE * short))
    aspect = math.sqrt(rng.uniform(*_ASPECT_RANGE))
    return min(round(side * aspect), int(0.9 * frame[0])), min(round(side / aspect), int(0.9 * frame[1]))


def _boxes(frame: tuple[int, int], size: tuple[int, int]) -> np.ndarray:
    """Every candidate position of a ``size`` rectangle in ``frame``, an eighth of its side apart, shape (M, 4)."""
    step = max(1, min(size) // 8)
    xs, ys = (np.unique(np.r_[np.arange(0, f - s + 1, step), f - s]) for f, s in zip(frame, size))
    x, y = np.meshgrid(xs, ys)
    return np.stack([x.ravel(), y.ravel(), np.full(x.size, size[0]), np.full(x.size, size[1])], axis=1)


def _distances(boxes: np.ndarray, frame: tuple[int, int]) -> np.ndarray:
    """Each box centre's distance from the frame's centre, as a share of its half-diagonal."""
    cx = boxes[:, 0] + boxes[:, 2] / 2 - frame[0] / 2
    cy = boxes[:, 1] + boxes[:, 3] / 2 - frame[1] / 2
    return np.hypot(cx, cy) / (math.hypot(*frame) / 2)


def _clipped(segments: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Length of each segment's part inside each box (Liang-Barsky clipping), shape (M boxes, N segments)."""
    x0, y0, x1, y1 = (segments[:, i][None, :] for i in range(4))
    bx, by, bw, bh = (boxes[:, i][:, None].astype(float) for i in range(4))
    dx, dy = x1 - x0, y1 - y0
    enter = np.zeros((len(boxes), len(segments)))
    leave = np.ones_like(enter)
    outside = np.zeros(enter.shape, bool)
    for p, q in ((-dx, x0 - bx), (dx, bx + bw - x0), (-dy, y0 - by), (dy, by + bh - y0)):
        with np.errstate(divide="ignore", invalid="ignore"):
            t = q / p
        enter = np.where(p < 0, np.maximum(enter, t), enter)
        leave = np.where(p > 0, np.minimum(leave, t), leave)
        outside |= (p == 0) & (q < 0)
    return np.where(outside, 0.0, np.clip(leave - enter, 0, None)) * np.hypot(dx, dy)


def _region(segments: np.ndarray, boxes: np.ndarray, long: float) -> Region:
    """The box whose long edges inside add up longest (the first of equals), with those edges' figures."""
    inside = _clipped(segments, boxes)
    inside = np.where(inside >= long, inside, 0.0)
    best = int(np.argmax(inside.sum(axis=1)))
    kept = segments[inside[best] > 0]
    angles = np.degrees(np.arctan2(kept[:, 3] - kept[:, 1], kept[:, 2] - kept[:, 0])) % 180
    apart = np.abs(angles[:, None] - angles[None, :])
    two = bool((np.minimum(apart, 180 - apart) > _TWO_DIRECTIONS_DEG).any())
    box = tuple(int(v) for v in boxes[best])
    return Region(box, round(float(inside[best].sum()), 1), len(kept), two)


def _overlaps(boxes: np.ndarray, box: Box) -> np.ndarray:
    x, y, w, h = box
    return ((boxes[:, 0] < x + w) & (x < boxes[:, 0] + boxes[:, 2])
            & (boxes[:, 1] < y + h) & (y < boxes[:, 1] + boxes[:, 3]))


def _destination(rng: np.random.Generator, frame: tuple[int, int], size: tuple[int, int], source: Box,
                 allowed: Callable[[np.ndarray], np.ndarray] | None = None) -> Box:
    """A random position for the piece, clear of its source where ``allowed`` leaves room for that."""
    boxes = _boxes(frame, size)
    allowed = np.ones(len(boxes), bool) if allowed is None else allowed(boxes)
    clear = allowed & ~_overlaps(boxes, source)
    pool = np.flatnonzero(clear if clear.any() else allowed)
    return tuple(int(v) for v in boxes[pool[rng.integers(len(pool))]])


def _paste(plan: Plan, host: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, Paste]:
    """The forged pixels and what was pasted where, for a plan of one of the three kinds."""
    frame = plan.host.size
    long = _LONG_EDGE_SHARE * min(frame)
    size = _piece_size(rng, frame)
    scale, donor_size = None, None
    if plan.kind == OTHER_CAMERA:
        donor = plan.donor
        factor = max(frame) / max(donor.size)
        donor_size = (round(donor.size[0] * factor), round(donor.size[1] * factor))
        size = (min(size[0], int(0.9 * donor_size[0])), min(size[1], int(0.9 * donor_size[1])))
        inset = round(rng.uniform(0, _CORNER_INSET_SHARE) * min(frame))
        corner = int(rng.integers(4))
        x = inset if corner % 2 == 0 else frame[0] - size[0] - inset
        y = inset if corner < 2 else frame[1] - size[1] - inset
        destination = (x, y, *size)
        there = float(_distances(np.array([destination]), frame)[0])
        boxes = _boxes(donor_size, size)
        boxes = boxes[np.abs(_distances(boxes, donor_size) - there) >= _MIN_DISTANCE_CHANGE]
        scaled = donor.segments * np.array([donor_size[0] / donor.size[0], donor_size[1] / donor.size[1]] * 2)
        source = _region(scaled, boxes, long)
        with Image.open(donor.path) as img:
            resized = img.convert("RGB").resize(donor_size, Image.Resampling.LANCZOS)
        sx, sy, w, h = source.box
        piece = np.asarray(resized.crop((sx, sy, sx + w, sy + h)))
        source_frame = donor_size
    elif plan.kind == MOVED:
        source = _region(plan.host.segments, _boxes(frame, size), long)
        here = float(_distances(np.array([source.box]), frame)[0])
        destination = _destination(rng, frame, size, source.box,
                                   lambda b: np.abs(_distances(b, frame) - here) >= _MIN_DISTANCE_CHANGE)
        sx, sy, w, h = source.box
        piece = host[sy:sy + h, sx:sx + w]
        source_frame = frame
    else:
        low, high = _SCALE_RANGES[int(rng.integers(len(_SCALE_RANGES)))]
        scale = round(float(rng.uniform(low, high)), 3)
        source_size = (min(round(size[0] / scale), int(0.9 * frame[0])), min(round(size[1] / scale), int(0.9 * frame[1])))
        size = (round(source_size[0] * scale), round(source_size[1] * scale))
        source = _region(plan.host.segments, _boxes(frame, source_size), long)
        destination = _destination(rng, frame, size, source.box)
        sx, sy, w, h = source.box
        piece = np.asarray(Image.fromarray(host[sy:sy + h, sx:sx + w]).resize(size, Image.Resampling.LANCZOS))
        source_frame = frame
    forged = host.copy()
    x, y, w, h = destination
    forged[y:y + h, x:x + w] = piece
    distances = (round(float(_distances(np.array([source.box]), source_frame)[0]), 3),
                 round(float(_distances(np.array([destination]), frame)[0]), 3))
    return forged, Paste(source, destination, scale, donor_size, distances)


def _make(plan: Plan, host: np.ndarray, folder: Path) -> tuple[dict[str, object], dict[str, str]]:
    """Forge (or, for a control, only re-save) one case into ``folder``; its recipe and its ``truth.csv`` row."""
    paste = None
    mask = None
    pixels = host
    if plan.kind != CONTROL:
        pixels, paste = _paste(plan, host, np.random.default_rng(plan.seed))
        mask = np.zeros(host.shape[:2], np.uint8)
        x, y, w, h = paste.destination
        mask[y:y + h, x:x + w] = 255
    image = Image.fromarray(pixels)
    mask_image = None if mask is None else Image.fromarray(mask)
    if plan.export.resize is not None:
        image, mask_image = downscaled(image, mask_image, plan.export.resize)
    photo = f"{plan.name}.jpg"
    # Pillow writes EXIF only when given it: forgers' exports vary, and none is claimed here.
    image.save(folder / photo, format="JPEG", quality=plan.export.quality, subsampling=_SUBSAMPLING)
    mask_file = save_mask(folder, plan.name, mask_image)
    recipe = {
        "name": plan.name, "file": photo, "label": "authentic" if paste is None else "spliced", "kind": plan.kind,
        "mask": mask_file, "seed": plan.seed, "host": plan.host.describe(),
        "donor": None if plan.donor is None else {**plan.donor.describe(), "resized_to": list(paste.donor_size)},
        "source": None if paste is None else list(paste.source.box),
        "destination": None if paste is None else list(paste.destination),
        "scale": None if paste is None else paste.scale,
        "distance_from_centre": None if paste is None else dict(zip(("source", "destination"), paste.distances)),
        "region": None if paste is None else {"edge_length_px": paste.source.edge_length, "edges": paste.source.edges,
                                               "two_directions": paste.source.two_directions},
        "export": {"jpeg_quality": plan.export.quality, "resize": plan.export.resize, "size": list(image.size),
                   "subsampling": _SUBSAMPLING, "exif": False},
    }
    row = {
        "file": photo, "label": recipe["label"], "mask": mask_file or "", "kind": plan.kind,
        "jpeg_quality": str(plan.export.quality), "resized": "no" if plan.export.resize is None else "yes",
        "host": plan.host.name, "donor": "" if plan.donor is None else plan.donor.name,
        "two_directions": "" if paste is None else ("yes" if paste.source.two_directions else "no"),
    }
    return recipe, row
