"""Authentic photos processed as editors and platforms do: the suite ``forensics validate innocent-processing``.

A detector of manipulation must not convict a photo that was only processed:
corrected for its lens, straightened, cropped, resized, toned, sharpened,
denoised, re-encoded by a platform or exported losslessly. Every such photo is
authentic by construction, since nothing is inserted, moved or removed, so
the share a detector convicts is its false-alarm rate on innocent processing.
This module makes those photos from the authentic photos of the real corpus's
``authentic_buildings/*`` sets (default ``../shared/data/real``) but
``opensfm_lund``, whose photos OpenSfM's authors had already downscaled to
1024 px. The photos are for research use only, so they are only read, and the
suite is built on demand into a folder outside the repository, never
committed. Each case applies one chain to one photo decoded by Pillow on its
stored pixel grid (EXIF Orientation ignored) and saves it with Pillow,
without EXIF:

``lens_correction``
    OpenCV's undistortion (``initUndistortRectifyMap`` and ``remap``, as
    ``cv2.undistort``) of a one-term radial model, k1 in [-0.10, -0.04] or
    [0.03, 0.08], focal length 0.9 times the larger side, principal point at
    the centre; of every 16 cases, 8 with the new camera matrix filling the
    frame (alpha 0, an editor's crop-to-fill) and 8 keeping the camera
    matrix (``cv2.undistort``'s default: no zoom, the frame's scale kept at
    the centre, where the warp is nearest the identity); each of the nearest,
    linear, cubic and Lanczos-4 interpolations equally often in both, and
    half of each at JPEG quality 98 or 100 (where resampling that keeps
    the old JPEG grid's traces is a known false alarm), half at 85, 92 or 95;
``rotation``
    0.5-3 degrees either way, Pillow bicubic, cropped to the largest
    axis-aligned rectangle inside the rotated frame;
``keystone``
    a vertical perspective correction (``cv2.warpPerspective``, linear or
    cubic): the top or bottom corners 2-6 % of the width inward mapped to
    the frame's corners;
``crop``
    70-95 % of each side, at offsets that are not multiples of 8;
``resize_down``, ``resize_up``
    by 0.5-0.8 or 1.1-1.5, Pillow bilinear, bicubic or Lanczos;
``levels_gamma``
    black point 0-12, white point 240-255, gamma 0.8-1.25;
``unsharp_mask``
    Pillow's ``UnsharpMask``, radius 0.8-2.5 px, 50-150 %, threshold 0-4;
``noise_reduction``
    OpenCV's bilateral filter, 5 or 7 px, colour sigma 15-35, space sigma 3-6;
``platform_reencode``
    the longer side brought down to 1600 or 2048 px (Pillow bilinear,
    bicubic or Lanczos; a smaller photo keeps its size), JPEG quality 70-85,
    4:2:0;
``png_export``
    the decoded photo as a lossless PNG.

The other chains save JPEG at a quality of 85-100 with the chroma
subsampling 4:4:4 or 4:2:0. Each chain takes its hosts one photo of each
camera before a second of any, in an order of its own.

The suite folder holds the photos, ``truth.csv`` (read by :mod:`.cases`;
every label ``authentic``; conditions ``kind``, ``jpeg_quality``, ``host``,
``interpolation`` for the chains that resample, ``subsampling``) and
``recipes.json``: every case's source photo with its SHA-256, its chain's
settings, its export and its own seed. The same corpus and seed give the same
files.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import TypeVar

import numpy as np
from PIL import Image, ImageFilter

from .cases import Suite, folder_suite
from .real_corpus import RealPhoto, camera_turns, read_photos, write_suite

INNOCENT_PROCESSING = "innocent-processing"
LENS_CORRECTION = "lens_correction"
#: Its photos are OpenSfM's 1024 px copies: a camera's own traces are gone before any processing here.
_SKIPPED_SETS = frozenset({"opensfm_lund"})
_HEADER = ("file", "label", "kind", "jpeg_quality", "host", "interpolation", "subsampling")

_QUALITY_RANGE = (85, 100)
_SUBSAMPLINGS = ("4:4:4", "4:2:0")
_LENS_QUALITIES = ((98, 100), (85, 92, 95))
_LENS_INTERPOLATIONS = ("nearest", "linear", "cubic", "lanczos4")
_K1_RANGES = ((-0.10, -0.04), (0.03, 0.08))
_FOCAL_SHARE = 0.9
_ROTATION_DEG = (0.5, 3.0)
#: Bicubic weights reach two pixels out: the crop stays that far inside the rotated photo's edge.
_ROTATION_MARGIN_PX = 2
_KEYSTONE_SHARE = (0.02, 0.06)
_KEYSTONE_INTERPOLATIONS = ("linear", "cubic")
_CROP_KEPT = (0.7, 0.95)
_RESIZE_DOWN = (0.5, 0.8)
_RESIZE_UP = (1.1, 1.5)
_RESAMPLINGS = ("bilinear", "bicubic", "lanczos")
_BLACK_POINT = (0, 12)
_WHITE_POINT = (240, 255)
_GAMMA = (0.8, 1.25)
_USM_RADIUS_PX = (0.8, 2.5)
_USM_PERCENT = (50, 150)
_USM_THRESHOLD = (0, 4)
_BILATERAL_DIAMETERS = (5, 7)
_BILATERAL_SIGMA_COLOR = (15.0, 35.0)
_BILATERAL_SIGMA_SPACE = (3.0, 6.0)
_PLATFORM_SIDES = (1600, 2048)
_PLATFORM_QUALITY = (70, 85)
_PLATFORM_SUBSAMPLING = "4:2:0"

Settings = Mapping[str, object]
"""A chain's drawn settings, as written to ``recipes.json``."""
T = TypeVar("T")


@dataclass(frozen=True)
class SuiteSize:
    """How many lens corrections, and how many cases of each other chain."""

    lens_correction: int = 24
    per_chain: int = 10


@dataclass(frozen=True)
class Export:
    """How the processed photo is saved: ``JPEG`` with a quality and chroma subsampling, or ``PNG``."""

    format: str
    quality: int | None
    subsampling: str | None

    @property
    def suffix(self) -> str:
        return ".jpg" if self.format == "JPEG" else ".png"


@dataclass(frozen=True)
class Chain:
    """A processing chain.

    ``draw`` gives the settings of its ``index``-th case from the case's
    generator and the photo's size, ``export`` how that case is saved, and
    ``apply`` processes an RGB ``uint8`` photo with the settings.
    """

    name: str
    draw: Callable[[np.random.Generator, int, tuple[int, int]], dict[str, object]]
    apply: Callable[[np.ndarray, Settings], np.ndarray]
    export: Callable[[np.random.Generator, int], Export]


@dataclass(frozen=True)
class Plan:
    """One case before it is made: its chain's settings and export, drawn from ``seed``."""

    name: str
    chain: Chain
    host: RealPhoto
    seed: int
    settings: Settings
    export: Export


def build_innocent_processing(corpus: Path, folder: Path, seed: int,
                              size: SuiteSize = SuiteSize()) -> list[dict[str, object]]:
    """Process the corpus's photos into ``folder`` (see this module's docstring).

    Parameters
    ----------
    corpus : Path
        Only read: the folder whose ``authentic_buildings/<set>/`` folders hold
        the photos beside their ``truth.csv`` and ``exif.csv``.
    folder : Path
        Receives the processed photos, ``truth.csv`` and ``recipes.json``; made
        if absent, and files of those names in it are overwritten.
    seed : int
        Chooses the hosts and every chain's settings and export.
    size : SuiteSize
        Cases per chain.

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
    plans = _plan(read_photos(corpus, INNOCENT_PROCESSING, _SKIPPED_SETS), seed, size)
    folder.mkdir(parents=True, exist_ok=True)
    made = {}
    for host in dict.fromkeys(p.host for p in plans):
        # Each photo is decoded once for all its cases.
        with Image.open(host.path) as img:
            pixels = np.asarray(img.convert("RGB"))
        made |= {plan.name: _make(plan, pixels, folder) for plan in plans if plan.host is host}
    method = {
        "pixel_grid": "stored, EXIF Orientation ignored; decoded by Pillow to RGB uint8",
        "lens_correction": "cv2.initUndistortRectifyMap (CV_16SC2) and cv2.remap with replicated border; camera "
                           f"matrix f = {_FOCAL_SHARE:g} x larger side, principal point ((w-1)/2, (h-1)/2); "
                           "new camera matrix from cv2.getOptimalNewCameraMatrix, alpha 0, centred",
        "rotation": "Pillow Image.rotate, bicubic, about the centre; crop to the largest axis-aligned rectangle "
                    f"inside, {_ROTATION_MARGIN_PX} px in",
        "keystone": "cv2.getPerspectiveTransform of the inset corners to the frame's, cv2.warpPerspective with "
                    "replicated border",
        "resampling": "Pillow Image.resize (resize_down, resize_up, platform_reencode)",
        "levels_gamma": "float: clip((v - black) / (white - black), 0, 1) ** (1 / gamma) x 255, rounded",
        "noise_reduction": "cv2.bilateralFilter",
        "export": "Pillow, no EXIF, ICC or XMP written; JPEG with the recorded quality and subsampling, or PNG",
    }
    return write_suite(folder, INNOCENT_PROCESSING, corpus, seed, size, method, [made[p.name] for p in plans],
                       _HEADER)


def innocent_processing_suite(corpus: Path, folder: Path, seed: int, size: SuiteSize = SuiteSize()) -> Suite:
    """Build the suite into ``folder`` (:func:`build_innocent_processing`) and read it as a folder suite."""
    build_innocent_processing(corpus, folder, seed, size)
    return replace(folder_suite(folder), name=INNOCENT_PROCESSING, source=f"{corpus.resolve()} (seed {seed})")


def _plan(photos: list[RealPhoto], seed: int, size: SuiteSize) -> list[Plan]:
    """Hosts, case seeds, settings and exports: every draw of the suite."""
    rng = np.random.default_rng(seed)
    plans = []
    for chain in CHAINS:
        # Turns drawn afresh for each chain: its hosts span as many cameras as there are, each a photo of its own.
        hosts = camera_turns(photos, rng)
        for i in range(size.lens_correction if chain.name == LENS_CORRECTION else size.per_chain):
            host = hosts[i % len(hosts)]
            case_seed = int(rng.integers(2**31))
            case_rng = np.random.default_rng(case_seed)
            plans.append(Plan(f"{chain.name}_{i + 1:03d}", chain, host, case_seed, chain.draw(case_rng, i, host.size),
                              chain.export(case_rng, i)))
    return plans


def _make(plan: Plan, pixels: np.ndarray, folder: Path) -> tuple[dict[str, object], dict[str, str]]:
    """Process and save one case into ``folder``; its recipe and its ``truth.csv`` row."""
    image = Image.fromarray(plan.chain.apply(pixels, plan.settings))
    export = plan.export
    photo = plan.name + export.suffix
    # Pillow writes EXIF only when given it: editors' and platforms' exports vary, and none is claimed here.
    if export.format == "PNG":
        image.save(folder / photo, format="PNG")
    else:
        image.save(folder / photo, format="JPEG", quality=export.quality, subsampling=export.subsampling)
    recipe = {
        "name": plan.name, "file": photo, "label": "authentic", "kind": plan.chain.name, "seed": plan.seed,
        "host": plan.host.describe(), "settings": dict(plan.settings),
        "export": {"format": export.format, "jpeg_quality": export.quality, "subsampling": export.subsampling,
                   "size": list(image.size), "exif": False},
    }
    row = {
        "file": photo, "label": "authentic", "kind": plan.chain.name,
        "jpeg_quality": "" if export.quality is None else str(export.quality), "host": plan.host.name,
        "interpolation": str(plan.settings.get("interpolation") or ""), "subsampling": export.subsampling or "",
    }
    return recipe, row


def _uniform(rng: np.random.Generator, bounds: tuple[float, float], digits: int = 3) -> float:
    """A draw rounded as the recipe writes it, so that the recipe alone remakes the photo."""
    return round(float(rng.uniform(*bounds)), digits)


def _integer(rng: np.random.Generator, bounds: tuple[int, int]) -> int:
    return int(rng.integers(bounds[0], bounds[1] + 1))


def _pick(rng: np.random.Generator, options: tuple[T, ...]) -> T:
    return options[int(rng.integers(len(options)))]


def _editor_export(rng: np.random.Generator, index: int) -> Export:
    return Export("JPEG", _integer(rng, _QUALITY_RANGE), _pick(rng, _SUBSAMPLINGS))


def _lens_export(rng: np.random.Generator, index: int) -> Export:
    # Alternating keeps half of every interpolation's cases at 98-100, whatever the count.
    return Export("JPEG", _pick(rng, _LENS_QUALITIES[index % 2]), _pick(rng, _SUBSAMPLINGS))


def _platform_export(rng: np.random.Generator, index: int) -> Export:
    return Export("JPEG", _integer(rng, _PLATFORM_QUALITY), _PLATFORM_SUBSAMPLING)


def _png_export(rng: np.random.Generator, index: int) -> Export:
    return Export("PNG", None, None)


def _draw_lens(rng: np.random.Generator, index: int, size: tuple[int, int]) -> dict[str, object]:
    return {"k1": _uniform(rng, _pick(rng, _K1_RANGES), 4), "focal_px": round(_FOCAL_SHARE * max(size), 2),
            "centre": [(size[0] - 1) / 2, (size[1] - 1) / 2],
            "interpolation": _LENS_INTERPOLATIONS[index // 2 % len(_LENS_INTERPOLATIONS)],
            # Decided by the index, not drawn, so that the other cases' draws stay as they were.
            "fill_frame": index // (2 * len(_LENS_INTERPOLATIONS)) % 2 == 0}


def _lens_correction(pixels: np.ndarray, settings: Settings) -> np.ndarray:
    import cv2

    h, w = pixels.shape[:2]
    f, (cx, cy) = settings["focal_px"], settings["centre"]
    camera = np.array([[f, 0, cx], [0, f, cy], [0, 0, 1]])
    distortion = np.array([settings["k1"], 0, 0, 0])
    # An editor's crop-to-fill: alpha 0 scales so that every output pixel comes from the photo. Without it the
    # camera matrix is kept, as cv2.undistort does, and the corners take the border's pixels.
    new = cv2.getOptimalNewCameraMatrix(camera, distortion, (w, h), 0, (w, h), centerPrincipalPoint=True)[0] \
        if settings.get("fill_frame", True) else camera
    maps = cv2.initUndistortRectifyMap(camera, distortion, None, new, (w, h), cv2.CV_16SC2)
    return cv2.remap(pixels, *maps, _opencv(settings["interpolation"]), borderMode=cv2.BORDER_REPLICATE)


def _opencv(interpolation: object) -> int:
    """OpenCV's flag for an interpolation as the recipe names it: nearest, linear, cubic or lanczos4."""
    import cv2

    return getattr(cv2, f"INTER_{str(interpolation).upper()}")


def _draw_rotation(rng: np.random.Generator, index: int, size: tuple[int, int]) -> dict[str, object]:
    degrees = _uniform(rng, _ROTATION_DEG) * _pick(rng, (-1, 1))
    return {"degrees": degrees, "crop": list(_inner_box(size, degrees)), "interpolation": "bicubic"}


def _inner_box(size: tuple[int, int], degrees: float) -> tuple[int, int, int, int]:
    """The largest axis-aligned rectangle inside the frame rotated by ``degrees`` about its centre, as x, y, w, h.

    The closed form is the one for a rectangle touching all four rotated
    sides, which it does while sin(2 angle) times the longer side is below the
    shorter: for 3 degrees, any photo up to 9.5 times as long as high.
    """
    w, h = size
    a = math.radians(abs(degrees))
    cos2 = math.cos(2 * a)
    inner_w = int((w * math.cos(a) - h * math.sin(a)) / cos2) - 2 * _ROTATION_MARGIN_PX
    inner_h = int((h * math.cos(a) - w * math.sin(a)) / cos2) - 2 * _ROTATION_MARGIN_PX
    return (w - inner_w) // 2, (h - inner_h) // 2, inner_w, inner_h


def _rotation(pixels: np.ndarray, settings: Settings) -> np.ndarray:
    x, y, w, h = settings["crop"]
    rotated = Image.fromarray(pixels).rotate(settings["degrees"], resample=Image.Resampling.BICUBIC)
    return np.asarray(rotated.crop((x, y, x + w, y + h)))


def _draw_keystone(rng: np.random.Generator, index: int, size: tuple[int, int]) -> dict[str, object]:
    return {"inset": _uniform(rng, _KEYSTONE_SHARE, 4), "edge": _pick(rng, ("top", "bottom")),
            "interpolation": _pick(rng, _KEYSTONE_INTERPOLATIONS)}


def _keystone(pixels: np.ndarray, settings: Settings) -> np.ndarray:
    import cv2

    h, w = pixels.shape[:2]
    frame = np.float32([[0, 0], [w - 1, 0], [w - 1, h - 1], [0, h - 1]])
    inset = settings["inset"] * w
    # Converging verticals are corrected by spreading the narrow edge's corners out to the frame's.
    left, right = (0, 1) if settings["edge"] == "top" else (3, 2)
    source = frame.copy()
    source[left, 0] += inset
    source[right, 0] -= inset
    return cv2.warpPerspective(pixels, cv2.getPerspectiveTransform(source, frame), (w, h),
                               flags=_opencv(settings["interpolation"]), borderMode=cv2.BORDER_REPLICATE)


def _draw_crop(rng: np.random.Generator, index: int, size: tuple[int, int]) -> dict[str, object]:
    (x, w), (y, h) = (_crop_span(rng, side) for side in size)
    return {"box": [x, y, w, h]}


def _crop_span(rng: np.random.Generator, side: int) -> tuple[int, int]:
    """Offset and length of a crop along one side."""
    kept = round(side * rng.uniform(*_CROP_KEPT))
    offset = int(rng.integers(1, side - kept + 1))
    # Off the 8 x 8 grid, so that the old JPEG blocks no longer line up with the new ones.
    return (offset - 1 if offset % 8 == 0 else offset), kept


def _crop(pixels: np.ndarray, settings: Settings) -> np.ndarray:
    x, y, w, h = settings["box"]
    return pixels[y:y + h, x:x + w]


def _draw_resize(bounds: tuple[float, float], rng: np.random.Generator, index: int,
                 size: tuple[int, int]) -> dict[str, object]:
    factor = _uniform(rng, bounds)
    return {"factor": factor, "size": [round(size[0] * factor), round(size[1] * factor)],
            "interpolation": _pick(rng, _RESAMPLINGS)}


def _resize(pixels: np.ndarray, settings: Settings) -> np.ndarray:
    if settings["size"] is None:
        return pixels
    resample = Image.Resampling[str(settings["interpolation"]).upper()]
    return np.asarray(Image.fromarray(pixels).resize(tuple(settings["size"]), resample))


def _draw_levels(rng: np.random.Generator, index: int, size: tuple[int, int]) -> dict[str, object]:
    return {"black": _integer(rng, _BLACK_POINT), "white": _integer(rng, _WHITE_POINT), "gamma": _uniform(rng, _GAMMA)}


def _levels_gamma(pixels: np.ndarray, settings: Settings) -> np.ndarray:
    black, white = settings["black"], settings["white"]
    spread = np.clip((pixels.astype(np.float32) - black) / (white - black), 0, 1)
    return np.rint(spread ** (1 / settings["gamma"]) * 255).astype(np.uint8)


def _draw_unsharp(rng: np.random.Generator, index: int, size: tuple[int, int]) -> dict[str, object]:
    return {"radius_px": _uniform(rng, _USM_RADIUS_PX, 2), "percent": _integer(rng, _USM_PERCENT),
            "threshold": _integer(rng, _USM_THRESHOLD)}


def _unsharp_mask(pixels: np.ndarray, settings: Settings) -> np.ndarray:
    sharpen = ImageFilter.UnsharpMask(settings["radius_px"], settings["percent"], settings["threshold"])
    return np.asarray(Image.fromarray(pixels).filter(sharpen))


def _draw_denoise(rng: np.random.Generator, index: int, size: tuple[int, int]) -> dict[str, object]:
    return {"diameter_px": _pick(rng, _BILATERAL_DIAMETERS), "sigma_color": _uniform(rng, _BILATERAL_SIGMA_COLOR, 1),
            "sigma_space": _uniform(rng, _BILATERAL_SIGMA_SPACE, 1)}


def _noise_reduction(pixels: np.ndarray, settings: Settings) -> np.ndarray:
    import cv2

    return cv2.bilateralFilter(pixels, settings["diameter_px"], settings["sigma_color"], settings["sigma_space"])


def _draw_platform(rng: np.random.Generator, index: int, size: tuple[int, int]) -> dict[str, object]:
    side = _pick(rng, _PLATFORM_SIDES)
    if max(size) <= side:
        # Platforms pass a photo already within their limit through at its size.
        return {"longer_side": side, "size": None, "interpolation": None}
    factor = side / max(size)
    return {"longer_side": side, "size": [round(size[0] * factor), round(size[1] * factor)],
            "interpolation": _pick(rng, _RESAMPLINGS)}


def _draw_nothing(rng: np.random.Generator, index: int, size: tuple[int, int]) -> dict[str, object]:
    return {}


def _unchanged(pixels: np.ndarray, settings: Settings) -> np.ndarray:
    return pixels


#: The chains in the suite's order.
CHAINS = (
    Chain(LENS_CORRECTION, _draw_lens, _lens_correction, _lens_export),
    Chain("rotation", _draw_rotation, _rotation, _editor_export),
    Chain("keystone", _draw_keystone, _keystone, _editor_export),
    Chain("crop", _draw_crop, _crop, _editor_export),
    Chain("resize_down", partial(_draw_resize, _RESIZE_DOWN), _resize, _editor_export),
    Chain("resize_up", partial(_draw_resize, _RESIZE_UP), _resize, _editor_export),
    Chain("levels_gamma", _draw_levels, _levels_gamma, _editor_export),
    Chain("unsharp_mask", _draw_unsharp, _unsharp_mask, _editor_export),
    Chain("noise_reduction", _draw_denoise, _noise_reduction, _editor_export),
    Chain("platform_reencode", _draw_platform, _resize, _platform_export),
    Chain("png_export", _draw_nothing, _unchanged, _png_export),
)
