"""Spliced synthetic photos: the paper's three kinds of splice (sec. 4.2), with mask and truth.

``copy_move``
    a region holding straight edges is copied within the photo to the mirror
    position across the vertical axis, so its edges bow the wrong way;
``other_camera``
    a region of a photo taken with a lens whose ``k1`` differs by 0.08 to 0.2
    (possibly of the other sign) replaces the same region of the host;
``other_zoom``
    a region of a photo of the same lens family at another focal length
    (``k1`` lower at the tele end, higher at the wide end, by 0.06 to 0.12) is
    resized by the zoom ratio and pasted.

The host of ``make_splice(kind, seed, ...)`` and its noise are those of
``render_authentic(seed, ...)`` (:mod:`.photo`), so the two differ only inside
the splice mask (before resizing and JPEG).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from .photo import PostProcessing, finish, image_params, render_authentic, resize_points, seed_streams
from .render import MIN_TRUTH_LENGTH_PX, Capture, polyline_runs, render_scene
from .scene import ConvexPolygon, Scene, random_scene
from .spec import KINDS
from .truth import PasteTruth, SynthImage

SPLICE_KINDS = KINDS[1:]

# Host edges closer than this to the paste boundary are not reported as the host's.
_SEAM_MARGIN_PX = 2.0


@dataclass(frozen=True)
class _Placement:
    """Region geometry of one paste, pixels of the unresized frame."""

    region: np.ndarray  # (4, 2) outline in the output
    source_centre: np.ndarray  # (2,)
    target_centre: np.ndarray  # (2,)
    scale: float


def _region_signed_distance(points: np.ndarray, region: np.ndarray) -> np.ndarray:
    """Signed distance of pixel points (N, 2) to a convex pixel outline (4, 2); negative inside."""
    return ConvexPolygon(region, np.zeros(3)).signed_distance(points[:, 0], points[:, 1])[0]


def _clip_lines(
    lines: list[np.ndarray], region: np.ndarray, inside: bool, margin: float, min_length: float
) -> list[np.ndarray]:
    """Pieces of polylines at least ``margin`` px inside (or outside) a region."""
    if not lines:
        return []
    pts = np.concatenate(lines)
    group = np.repeat(np.arange(len(lines)), [len(p) for p in lines])
    sd = _region_signed_distance(pts, region)
    keep = sd <= -margin if inside else sd >= margin
    return polyline_runs(pts, keep, group, min_length)


def _map_to_target(lines: list[np.ndarray], placement: _Placement) -> list[np.ndarray]:
    return [placement.target_centre + placement.scale * (p - placement.source_centre) for p in lines]


def _propose_placement(
    rng: np.random.Generator, kind: str, shape: tuple[int, int], scale: float, anchors: list[np.ndarray]
) -> _Placement | None:
    """One random region of 10-35 % of the frame around a long source edge, or None if it misfits."""
    h, w = shape
    height = rng.uniform(0.45, min(0.9, 0.95 * scale)) * h
    width = rng.uniform(0.12, 0.3) * w * h / height
    if width > min(0.9, 0.95 * scale) * w or width * height < 0.12 * w * h:
        return None
    anchor = anchors[rng.integers(len(anchors))]
    src_half = np.array([width, height]) / (2.0 * scale)
    mid = anchor[len(anchor) // 2]
    src = mid + rng.uniform(-0.3, 0.3, 2) * src_half * [1.0, 0.5]
    src = np.clip(src, src_half + 1.0, [w - 2.0, h - 2.0] - src_half)
    half = np.array([width, height]) / 2.0
    if kind == "copy_move":
        tgt = np.array([w - 1.0 - src[0], src[1] + rng.uniform(-0.1, 0.1) * h])
    else:
        tgt = src.copy()
    tgt = np.clip(tgt, half + 1.0, [w - 2.0, h - 2.0] - half)
    if kind == "copy_move":
        # A copy that lands near its own radius would carry nearly the right curvature.
        if abs(tgt[0] - src[0]) < 0.25 * w:
            return None
        tgt = np.round(tgt) - (src - np.round(src))
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=np.float64) * half
    jitter = rng.uniform(0.0, 0.05, (4, 2)) * half * -np.sign(corners)
    return _Placement(tgt + corners + jitter, src, tgt, scale)


def _place(
    rng: np.random.Generator,
    kind: str,
    shape: tuple[int, int],
    scale: float,
    source_lines: list[np.ndarray],
    feather: float,
) -> tuple[_Placement, list[np.ndarray], list[np.ndarray]] | None:
    """A placement whose pasted part holds at least two edges of a third of the frame height.

    Returns the placement, the pasted edges in output pixels and the same
    edges in source pixels, or None when no attempt succeeded.
    """
    h, w = shape
    long_px = h / 3.0
    anchors = [p for p in source_lines if abs(p[-1, 1] - p[0, 1]) * scale >= 1.05 * long_px]
    if kind == "copy_move":
        anchors = [p for p in anchors if abs(p[len(p) // 2, 0] - (w - 1) / 2.0) >= 0.15 * w]
    if not anchors:
        return None
    for _ in range(200):
        placement = _propose_placement(rng, kind, shape, scale, anchors)
        if placement is None:
            continue
        moved = _map_to_target(source_lines, placement)
        pasted = _clip_lines(moved, placement.region, True, feather + 1.0, MIN_TRUTH_LENGTH_PX)
        if sum(np.hypot(*(p[-1] - p[0])) >= long_px for p in pasted) >= 2:
            back = [placement.source_centre + (p - placement.target_centre) / placement.scale for p in pasted]
            return placement, pasted, back
    return None


def _alpha(shape: tuple[int, int], region: np.ndarray, feather: float) -> np.ndarray:
    """Paste opacity, (H, W) float32: 1 inside, ramping to 0 over ``feather`` px at the seam."""
    h, w = shape
    lo = np.clip(np.floor(region.min(axis=0)).astype(int), 0, None)
    hi = np.minimum(np.ceil(region.max(axis=0)).astype(int) + 1, [w, h])
    ys, xs = np.mgrid[lo[1] : hi[1], lo[0] : hi[0]]
    sd = _region_signed_distance(np.stack([xs.ravel(), ys.ravel()], 1).astype(np.float64), region)
    alpha = np.zeros(shape, dtype=np.float32)
    alpha[lo[1] : hi[1], lo[0] : hi[0]] = np.clip(-sd / feather, 0.0, 1.0).reshape(xs.shape)
    return alpha


def _transplant(host: np.ndarray, source: np.ndarray, placement: _Placement, alpha: np.ndarray) -> np.ndarray:
    """Blend the source pixels, moved and scaled per ``placement``, into the host where ``alpha > 0``.

    Cubic spline interpolation reproduces the source exactly at whole-pixel
    shifts (copy-move). A shrinking paste is low-passed first, as any resizing
    tool does, so it carries no aliasing that the host lacks.
    """
    rows, cols = np.nonzero(alpha)
    target = np.stack([cols, rows], axis=1).astype(np.float64)
    src = placement.source_centre + (target - placement.target_centre) / placement.scale
    sigma = 0.5 * np.sqrt(1.0 / placement.scale**2 - 1.0) if placement.scale < 1.0 else 0.0
    # Only a window around the sampled area is filtered; its margin lets the
    # spline prefilter's edge effect (decaying as 0.27^n) and the blur die out.
    margin = 12 + int(np.ceil(4.0 * sigma))
    lo = np.maximum(np.floor(src.min(axis=0)).astype(int) - margin, 0)
    hi = np.minimum(np.ceil(src.max(axis=0)).astype(int) + margin + 1, [source.shape[1], source.shape[0]])
    window = source[lo[1] : hi[1], lo[0] : hi[0]]
    if sigma > 0:
        window = ndimage.gaussian_filter(window, sigma=(sigma, sigma, 0.0), mode="nearest")
    coords = [src[:, 1] - lo[1], src[:, 0] - lo[0]]
    a = alpha[rows, cols]
    out = host.copy()
    for ch in range(3):
        values = ndimage.map_coordinates(window[..., ch], coords, order=3, mode="nearest")
        out[rows, cols, ch] = (1.0 - a) * host[rows, cols, ch] + a * values
    return np.clip(out, 0.0, 1.0)


def _donor_camera(kind: str, k1: float, rng: np.random.Generator) -> tuple[float, float]:
    """The source lens's ``k1`` and the paste's magnification.

    Another camera differs by 0.08-0.2 in either direction. Another zoom of the
    same lens is more pincushion at the tele end, whose larger picture the
    forger shrinks, or more barrel at the wide end, which the forger enlarges.
    """
    if kind == "other_camera":
        return k1 + rng.choice([-1.0, 1.0]) * rng.uniform(0.08, 0.2), 1.0
    tele = rng.random() < 0.5
    delta = rng.uniform(0.06, 0.12)
    return (k1 - delta, rng.uniform(0.55, 0.8)) if tele else (k1 + delta, rng.uniform(1.25, 1.6))


def make_splice(
    kind: str,
    seed: int,
    size: tuple[int, int] = (1600, 1200),
    k1: float = 0.08,
    k2: float = 0.0,
    centre: Sequence[float] = (0.0, 0.0),
    *,
    noise: float = 0.01,
    blur: float = 0.7,
    jpeg_quality: int | None = 90,
    resize: float | None = None,
    feather_px: float = 3.0,
) -> SynthImage:
    """A spliced photo of one of the paper's three kinds (sec. 4.2), with mask and truth.

    Parameters
    ----------
    kind : {"copy_move", "other_camera", "other_zoom"}
        "authentic" is accepted too and returns :func:`render_authentic`.
    seed : int
        The host scene and noise are those of ``render_authentic(seed, ...)``.
    size, k1, k2, centre, noise, blur, jpeg_quality, resize
        As in :func:`render_authentic`; the host camera's lens.
    feather_px : float
        Width of the blended seam inside the region, pixels.

    Returns
    -------
    SynthImage
        ``mask`` covers 10-35 % of the frame and its interior holds at least
        two straight edges of at least a third of the frame height
        (``paste.lines_px``).

    Raises
    ------
    ValueError
        For an unknown kind.
    RuntimeError
        If no region with two long edges was found (not seen in practice).
    """
    if kind == "authentic":
        post = {"noise": noise, "blur": blur, "jpeg_quality": jpeg_quality, "resize": resize}
        return render_authentic(seed, size, k1, k2, centre, **post)
    if kind not in SPLICE_KINDS:
        raise ValueError(f"unknown splice kind {kind!r}; expected one of {KINDS}")
    host_rng, noise_rng, splice_seq = seed_streams(seed)
    scene = random_scene(host_rng, size)
    host = render_scene(scene, size, k1, k2, centre, blur)
    shape = (size[1], size[0])
    found = _source_and_placement(kind, scene, host, size, blur, splice_seq, feather_px)
    source, placement, pasted, source_lines = found
    alpha = _alpha(shape, placement.region, feather_px)
    spliced = _transplant(host.image, source.image, placement, alpha)
    pixels, data, mask = finish(spliced, alpha, PostProcessing(noise, jpeg_quality, resize), noise_rng)
    out_shape = pixels.shape[:2]
    host_lines = _clip_lines(host.lines_px, placement.region, False, _SEAM_MARGIN_PX, MIN_TRUTH_LENGTH_PX)
    paste = PasteTruth(
        source_k1=float(source.k1),
        source_k2=float(source.k2),
        scale=float(placement.scale),
        source_centre_px=(float(placement.source_centre[0]), float(placement.source_centre[1])),
        target_centre_px=(float(placement.target_centre[0]), float(placement.target_centre[1])),
        region_px=resize_points(placement.region, shape, out_shape),
        lines_px=[resize_points(p, shape, out_shape) for p in pasted],
        source_lines_px=source_lines,
    )
    return SynthImage(
        image=pixels,
        jpeg_bytes=data,
        mask=mask,
        kind=kind,
        k1=float(k1),
        k2=float(k2),
        centre=host.centre,
        pasted_k1=None if kind == "copy_move" else float(source.k1),
        lines_px=[resize_points(p, shape, out_shape) for p in host_lines],
        seed=int(seed),
        params=image_params(kind, seed, size=size, k1=k1, k2=k2, centre=centre, noise=noise, blur=blur,
                            jpeg_quality=jpeg_quality, resize=resize, feather_px=feather_px),
        paste=paste,
    )


def _source_and_placement(
    kind: str, scene: Scene, host: Capture, size, blur: float, splice_seq: np.random.SeedSequence, feather: float
) -> tuple[Capture, _Placement, list[np.ndarray], list[np.ndarray]]:
    """The capture the pasted pixels come from and where they go.

    Copy-move takes them from the host itself. Otherwise a donor photo of
    another scene (same wall colour) is taken with the donor lens; a donor
    offering no suitable region is replaced by the next one of the stream.
    """
    shape = (size[1], size[0])
    for child in splice_seq.spawn(8):
        rng = np.random.default_rng(child)
        if kind == "copy_move":
            source, scale = host, 1.0
        else:
            donor_k1, scale = _donor_camera(kind, host.k1, rng)
            donor_scene = random_scene(rng, size, wall=scene.background)
            source = render_scene(donor_scene, size, donor_k1, host.k2, host.centre, blur)
        placed = _place(rng, kind, shape, scale, source.lines_px, feather)
        if placed is not None:
            return (source, *placed)
    raise RuntimeError(f"no region with two long straight edges found for {kind} splice")


def generate(params: dict) -> SynthImage:
    """Regenerate an image from its ``params`` (as stored in :attr:`SynthImage.params`)."""
    args = {k: v for k, v in params.items() if k not in ("kind", "seed")}
    args["size"] = tuple(args["size"])
    args["centre"] = tuple(args["centre"])
    if params["kind"] == "authentic":
        return render_authentic(params["seed"], **args)
    return make_splice(params["kind"], params["seed"], **args)
