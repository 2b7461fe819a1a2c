"""Manipulations made from real photos: the suite ``forensics validate realistic``.

The shared real corpus holds a few hundred manipulated photos, too few to
calibrate likelihood ratios beyond about LR 10 and too few kinds to say
which detector sees what. This module forges many more from the authentic
photos of the corpus's ``authentic_buildings/*`` sets (default
``../shared/data/real``, but ``opensfm_lund``, whose photos were downscaled
to 1024 px before anyone here saw them). The photos are for research use
only: they are only read, and the suite is built on demand into a folder
outside the repository, never committed. Each case takes one host photo,
decoded by Pillow on its stored pixel grid (EXIF Orientation ignored):

``splice``
    a region of another camera's photo pasted into the host: an object-like
    outline (a smooth random star-shaped curve, 1.5-8 % of the frame), its
    content cut at the same size from a random place of the donor, half of
    the time rescaled by 0.8-1.25 first, as a forger fits a piece;
``copy_move``
    a region of the host pasted elsewhere in it, moved only, or also rotated
    by 5-30 degrees, or scaled by 0.8-0.9 or 1.1-1.25 (OpenCV ``warpAffine``,
    bicubic); the truth is the destination, the source is recorded;
``removal``
    a region (0.3-1.5 % of the frame) filled in from its surroundings by
    OpenCV's inpainting (Telea's or Navier-Stokes), as an object is removed;
``control``
    the host itself, saved the same way: authentic.

Every forged region's edge is feathered by a Gaussian of 0, 1 or 2.5 px, as
an editor's soft brush does; its truth mask is where the pasted content
weighs half or more. Each case is then saved as forgers and platforms save:
JPEG at quality 70-100 (4:4:4 or 4:2:0), or downscaled by 0.5-0.9 (Lanczos)
and saved at 75-95, or as PNG. Controls are drawn from the same hosts and
exports, so that a detector is measured on the forgery and not on the save.
``truth.csv`` names each case's ``host`` photo and its ``scene``, the key
the host has in the corpus's own validation record: cross-validation grouped
by scene keeps a host's forgeries, its control and the host itself on one
side when the calibrators are fitted on both records.

What these cases cannot stand for: they are made by a program, not by a
person choosing what to hide and working until it looks right. The regions
are placed without regard for the scene (a piece may cut a building in
half), colours and lighting are not matched, no forger retouches the seam,
and each case holds one manipulation. A detector's figures on this suite are
evidence of what it sees in such traces on real camera photos, and an upper
bound on nothing: real forgeries may be easier (careless) or harder
(retouched, recompressed many times) than these.

The suite folder holds the photos, ``masks/*.png``, ``truth.csv`` (read by
:mod:`.cases`; conditions ``kind``, ``export``, ``jpeg_quality``,
``feather_px``, ``host``, ``donor``, ``scene``) and ``recipes.json``: every case's
source photos with their SHA-256, its region, transform and export, and its
own seed. The same corpus and seed give the same files.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np
from PIL import Image

from .cases import Suite, folder_suite
from .real_corpus import RealPhoto, camera_turns, downscaled, read_photos, save_mask, write_suite

REALISTIC = "realistic"
SPLICE, COPY_MOVE, REMOVAL, CONTROL = "splice", "copy_move", "removal", "control"
KINDS = (SPLICE, COPY_MOVE, REMOVAL)
_SKIPPED_SETS = frozenset({"opensfm_lund"})
_HEADER = ("file", "label", "mask", "kind", "export", "jpeg_quality", "feather_px", "host", "donor", "scene")

_AREA_SHARE = {SPLICE: (0.015, 0.08), COPY_MOVE: (0.015, 0.08), REMOVAL: (0.003, 0.015)}
_HARMONICS = 4
_FEATHERS_PX = (0.0, 1.0, 2.5)
_SPLICE_RESCALE = (0.8, 1.25)
_ROTATION_DEG = (5.0, 30.0)
_SCALES = ((0.8, 0.9), (1.1, 1.25))
_INPAINT = {"telea": cv2.INPAINT_TELEA, "navier_stokes": cv2.INPAINT_NS}
_INPAINT_RADIUS_PX = 5
_JPEG_QUALITY = (70, 100)
_RESIZE = (0.5, 0.9)
_RESIZED_QUALITY = (75, 95)
_SUBSAMPLINGS = ("4:4:4", "4:2:0")
#: Shares of the exports: JPEG as it is, downscaled then JPEG, PNG.
_EXPORT_WEIGHTS = (0.6, 0.25, 0.15)


@dataclass(frozen=True)
class SuiteSize:
    """How many forgeries of each kind; as many controls as forgeries in all.

    The default, 60 (360 photos), is the shipped record's size, on which
    the calibrators are fitted beside the real sets; it validates in about
    20 min on 2 cores (18 min measured, 2026-12-07).
    """

    per_kind: int = 60


@dataclass(frozen=True)
class Export:
    """How a case is saved: ``jpeg``, ``resized_jpeg`` (downscaled by ``resize`` first) or ``png``."""

    kind: str
    quality: int | None
    subsampling: str | None
    resize: float | None


@dataclass(frozen=True)
class Plan:
    """One case before it is made: everything drawn from the suite's seed."""

    name: str
    kind: str
    host: RealPhoto
    donor: RealPhoto | None
    seed: int
    export: Export


def build_realistic(corpus: Path, folder: Path, seed: int, size: SuiteSize = SuiteSize()) -> list[dict[str, object]]:
    """Forge the corpus's photos into ``folder`` (see this module's docstring).

    Parameters
    ----------
    corpus : Path
        Only read: the folder whose ``authentic_buildings/<set>/`` folders hold
        the photos beside their ``truth.csv`` and ``exif.csv``.
    folder : Path
        Receives the photos, ``masks/``, ``truth.csv`` and ``recipes.json``;
        made if absent, and files of those names in it are overwritten.
    seed : int
        Chooses the hosts, donors, regions, transforms and exports.
    size : SuiteSize
        Forgeries of each kind.

    Returns
    -------
    list of dict
        The recipes of ``recipes.json``, one a case in the suite's order.

    Raises
    ------
    SuiteError
        The corpus is absent, holds no set but ``opensfm_lund`` or holds a
        photo it cannot read.
    """
    plans = _plan(read_photos(corpus, REALISTIC, _SKIPPED_SETS), seed, size)
    (folder / "masks").mkdir(parents=True, exist_ok=True)
    made = [_make(plan, folder) for plan in plans]
    method = {
        "pixel_grid": "stored, EXIF Orientation ignored; decoded by Pillow to RGB uint8",
        "region": f"star-shaped curve r(t) = R (1 + sum of {_HARMONICS} harmonics, amplitude <= 0.25/k), filled by "
                  "cv2.fillPoly; feathered by a Gaussian; truth where the forged content weighs >= 1/2",
        "splice": "donor crop of the region's box at a random place, rescaled by Pillow LANCZOS half of the time",
        "copy_move": "cv2.warpAffine (bicubic, reflected border) moving the source region onto the destination",
        "removal": f"cv2.inpaint, radius {_INPAINT_RADIUS_PX} px, Telea or Navier-Stokes",
        "export": "Pillow, no EXIF, ICC or XMP; JPEG with the recorded quality and subsampling, LANCZOS downscale "
                  "before it for resized_jpeg (mask bilinear, >= 50 %), or PNG",
    }
    return write_suite(folder, REALISTIC, corpus, seed, size, method, made, _HEADER)


def realistic_suite(corpus: Path, folder: Path, seed: int, size: SuiteSize = SuiteSize()) -> Suite:
    """Build the suite into ``folder`` (:func:`build_realistic`) and read it as a folder suite."""
    build_realistic(corpus, folder, seed, size)
    return replace(folder_suite(folder), name=REALISTIC, source=f"{corpus.resolve()} (seed {seed})")


def _plan(photos: list[RealPhoto], seed: int, size: SuiteSize) -> list[Plan]:
    """Hosts, donors, case seeds and exports: every draw but the regions' own."""
    rng = np.random.default_rng(seed)
    plans = []
    for kind in KINDS:
        hosts = camera_turns(photos, rng)
        for i in range(size.per_kind):
            host = hosts[i % len(hosts)]
            others = [p for p in photos if p.camera != host.camera]
            donor = others[int(rng.integers(len(others)))] if kind == SPLICE and others else None
            if kind == SPLICE and donor is None:
                continue
            # A forgery and its control are saved alike, so that they differ by the forgery alone.
            export = _export(np.random.default_rng(int(rng.integers(2**31))))
            for label in (kind, CONTROL):
                case_seed = int(rng.integers(2**31))
                plans.append(Plan(f"{label}_{kind}_{i + 1:03d}" if label == CONTROL else f"{kind}_{i + 1:03d}",
                                  label, host, donor if label == SPLICE else None, case_seed, export))
    return plans


def _export(rng: np.random.Generator) -> Export:
    kind = str(rng.choice(["jpeg", "resized_jpeg", "png"], p=_EXPORT_WEIGHTS))
    if kind == "png":
        return Export(kind, None, None, None)
    subsampling = str(rng.choice(_SUBSAMPLINGS))
    if kind == "jpeg":
        return Export(kind, int(rng.integers(_JPEG_QUALITY[0], _JPEG_QUALITY[1] + 1)), subsampling, None)
    return Export(kind, int(rng.integers(_RESIZED_QUALITY[0], _RESIZED_QUALITY[1] + 1)), subsampling,
                  round(float(rng.uniform(*_RESIZE)), 3))


def blob(rng: np.random.Generator, shape: tuple[int, int], area_share: float) -> tuple[np.ndarray, tuple[float, float]]:
    """An object-like region: a smooth random star-shaped curve, filled.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the curve's harmonics and its place.
    shape : (int, int)
        ``(H, W)`` of the frame, pixels.
    area_share : float
        The region's area as a share of the frame's (about: the harmonics
        change it by a few percent).

    Returns
    -------
    mask : ndarray of bool, shape (H, W)
    centre : (float, float)
        ``(x, y)`` of the curve's centre, drawn so that the region stays
        inside the frame.

    Examples
    --------
    >>> mask, (x, y) = blob(np.random.default_rng(0), (400, 600), 0.05)
    >>> mask.shape, bool(0.035 < mask.mean() < 0.065)
    ((400, 600), True)
    """
    h, w = shape
    radius = np.sqrt(area_share * h * w / np.pi)
    k = np.arange(1, _HARMONICS + 1)
    amplitude = rng.uniform(0.0, 0.25 / k)
    phase = rng.uniform(0.0, 2 * np.pi, _HARMONICS)
    t = np.linspace(0.0, 2 * np.pi, 180, endpoint=False)
    r = radius * (1.0 + (amplitude[:, None] * np.cos(k[:, None] * t + phase[:, None])).sum(axis=0))
    reach = float(r.max()) + 2
    centre = (float(rng.uniform(reach, w - reach)), float(rng.uniform(reach, h - reach)))
    points = np.column_stack((centre[0] + r * np.cos(t), centre[1] + r * np.sin(t)))
    mask = np.zeros(shape, np.uint8)
    cv2.fillPoly(mask, [np.round(points).astype(np.int32)], 1)
    return mask.astype(bool), centre


def _alpha(mask: np.ndarray, feather_px: float) -> np.ndarray:
    """The forged content's weight, ``(H, W)`` float in [0, 1]: the mask, its edge softened."""
    alpha = mask.astype(np.float32)
    return cv2.GaussianBlur(alpha, (0, 0), feather_px) if feather_px > 0 else alpha


def _composite(host: np.ndarray, content: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    mixed = alpha[:, :, None] * content.astype(np.float32) + (1 - alpha[:, :, None]) * host.astype(np.float32)
    return np.clip(np.round(mixed), 0, 255).astype(np.uint8)


def _decode(photo: RealPhoto) -> np.ndarray:
    with Image.open(photo.path) as img:
        return np.asarray(img.convert("RGB"))


def _splice(host: np.ndarray, donor: np.ndarray, rng: np.random.Generator, mask: np.ndarray,
            ) -> tuple[np.ndarray, dict[str, object]]:
    """The donor's content under ``mask``: a crop of the region's box, rescaled half of the time."""
    ys, xs = np.nonzero(mask)
    y0, x0, bh, bw = ys.min(), xs.min(), ys.max() - ys.min() + 1, xs.max() - xs.min() + 1
    scale = round(float(rng.uniform(*_SPLICE_RESCALE)), 3) if rng.random() < 0.5 else 1.0
    dh, dw = donor.shape[:2]
    # A donor too small for the box is brought up to it: a forger enlarges a piece that does not fit.
    need = max(bh / (scale * dh), bw / (scale * dw), 1.0)
    if scale != 1.0 or need > 1.0:
        factor = scale * need
        donor = np.asarray(Image.fromarray(donor).resize((max(bw, round(dw * factor)), max(bh, round(dh * factor))),
                                                          Image.Resampling.LANCZOS))
        dh, dw = donor.shape[:2]
    sy, sx = int(rng.integers(0, dh - bh + 1)), int(rng.integers(0, dw - bw + 1))
    content = host.copy()
    content[y0:y0 + bh, x0:x0 + bw] = donor[sy:sy + bh, sx:sx + bw]
    return content, {"donor_box": [sx, sy, int(bw), int(bh)], "donor_scale": round(scale * need, 4)}


def _copy_move(host: np.ndarray, rng: np.random.Generator, mask: np.ndarray, centre: tuple[float, float],
               ) -> tuple[np.ndarray, dict[str, object]]:
    """The host moved (and rotated or scaled) so that a source region lands under ``mask``."""
    h, w = host.shape[:2]
    transform = str(rng.choice(["move", "rotate", "scale"]))
    angle = float(rng.uniform(*_ROTATION_DEG) * rng.choice([-1, 1])) if transform == "rotate" else 0.0
    scale = float(rng.uniform(*_SCALES[int(rng.integers(2))])) if transform == "scale" else 1.0
    ys, xs = np.nonzero(mask)
    half = max(xs.max() - xs.min(), ys.max() - ys.min()) / 2 + 2
    for _ in range(100):
        source = (float(rng.uniform(half, w - half)), float(rng.uniform(half, h - half)))
        if np.hypot(source[0] - centre[0], source[1] - centre[1]) > 2.2 * half:
            break
    # Rotation and scale about the source's centre, then the move onto the destination's.
    matrix = cv2.getRotationMatrix2D(source, angle, scale)
    matrix[:, 2] += np.array(centre) - np.array(source)
    moved = cv2.warpAffine(host, matrix, (w, h), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    return moved, {"transform": transform, "source_centre": [round(source[0], 1), round(source[1], 1)],
                   "angle_deg": round(angle, 2), "scale": round(scale, 3)}


def _removal(host: np.ndarray, rng: np.random.Generator, mask: np.ndarray) -> tuple[np.ndarray, dict[str, object]]:
    """The host with the region under ``mask`` filled in from around it."""
    method = str(rng.choice(sorted(_INPAINT)))
    filled = cv2.inpaint(np.ascontiguousarray(host[:, :, ::-1]), mask.astype(np.uint8), _INPAINT_RADIUS_PX,
                         _INPAINT[method])
    return np.ascontiguousarray(filled[:, :, ::-1]), {"inpainting": method}


def _make(plan: Plan, folder: Path) -> tuple[dict[str, object], dict[str, str]]:
    """Forge (or, for a control, only re-save) one case into ``folder``; its recipe and its ``truth.csv`` row."""
    rng = np.random.default_rng(plan.seed)
    host = _decode(plan.host)
    pixels, mask, forged = host, None, {}
    feather = 0.0
    if plan.kind != CONTROL:
        # Inpainting blends its own edge; a feathered paste is a brush's.
        feather = float(rng.choice(_FEATHERS_PX)) if plan.kind != REMOVAL else 0.0
        area = float(rng.uniform(*_AREA_SHARE[plan.kind]))
        mask, centre = blob(rng, host.shape[:2], area)
        if plan.kind == SPLICE:
            content, forged = _splice(host, _decode(plan.donor), rng, mask)
        elif plan.kind == COPY_MOVE:
            content, forged = _copy_move(host, rng, mask, centre)
        else:
            content, forged = _removal(host, rng, mask)
        alpha = _alpha(mask, feather)
        pixels = _composite(host, content, alpha)
        mask = alpha >= 0.5
        forged |= {"centre": [round(centre[0], 1), round(centre[1], 1)], "area_share": round(float(mask.mean()), 4)}
    image = Image.fromarray(pixels)
    mask_image = None if mask is None else Image.fromarray(mask.astype(np.uint8) * 255)
    export = plan.export
    if export.resize is not None:
        image, mask_image = downscaled(image, mask_image, export.resize)
    photo = f"{plan.name}.{'png' if export.kind == 'png' else 'jpg'}"
    if export.kind == "png":
        image.save(folder / photo, format="PNG")
    else:
        image.save(folder / photo, format="JPEG", quality=export.quality, subsampling=export.subsampling)
    mask_file = save_mask(folder, plan.name, mask_image)
    recipe = {
        "name": plan.name, "file": photo, "label": "authentic" if mask is None else "spliced", "kind": plan.kind,
        "mask": mask_file, "seed": plan.seed, "host": plan.host.describe(),
        "donor": None if plan.donor is None else plan.donor.describe(), "feather_px": feather, "forged": forged,
        "export": {"kind": export.kind, "jpeg_quality": export.quality, "subsampling": export.subsampling,
                   "resize": export.resize, "size": list(image.size), "exif": False},
    }
    row = {
        "file": photo, "label": recipe["label"], "mask": mask_file or "", "kind": plan.kind, "export": export.kind,
        "jpeg_quality": "" if export.quality is None else str(export.quality),
        "feather_px": "" if mask is None else f"{feather:g}", "host": plan.host.name,
        "donor": "" if plan.donor is None else plan.donor.name, "scene": plan.host.scene,
    }
    return recipe, row
