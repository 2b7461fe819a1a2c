"""Synthetic photos with known lens distortion, authentic and spliced, for validation.

A scene is a painter's list of flat shapes (convex polygons for walls, floors,
windows, poles and rails; rings and a sinusoidal cable as curved distractors)
over a textured wall, defined in *undistorted normalised* coordinates (see
:mod:`.geometry`). A camera renders it through the paper's radial model
(eqs. 1-5): every distorted pixel ``p_d`` shows the scene at
``p_u = undistort(p_d)``, which is closed form, so no inverse is needed.
Anti-aliasing is analytic rather than by supersampling: each shape's signed
distance is carried into distorted pixels through the model's Jacobian and
turned into the exact area of the pixel square on its inner side, so edges
keep their true sub-pixel curve (measured error about 1e-4 px). Optics blur
follows; sensor noise, resizing and JPEG are the post-processing that
authentic and spliced outputs share.

The three splices are those of the paper, sec. 4.2:

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

Every output carries its truth: the straight edges of the host, and of the
pasted part, as distorted polylines in pixels, the paste mask, and the
parameters that regenerate it. The host of ``make_splice(kind, seed, ...)``
and its noise are those of ``render_authentic(seed, ...)``, so the two differ
only inside the splice mask (before resizing and JPEG).
"""

from __future__ import annotations

import io
import json
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image
from scipy import ndimage

from forensics_core import SyntheticCase

from .geometry import distort, norm_scale, to_normalised, to_pixels, undistort
from .spec import KINDS

SPLICE_KINDS = KINDS[1:]

_LUMA = np.array([0.299, 0.587, 0.114])
# Half-side of the square, in undistorted normalised units, that the texture
# covers: the frame corners undistort to r_u <= 1.9 for k1 <= 0.3.
_TEXTURE_EXTENT = 2.5
_TEXTURE_SPACINGS = (0.04, 0.01)
# Parameter step of the truth polylines, in pixels of the host image.
_TRUTH_STEP_PX = 2.0
# Distance either side of an edge, in pixels, at which its contrast is judged.
_CONTRAST_OFFSET_PX = 1.5
_MIN_CONTRAST = 0.04
_MIN_TRUTH_LENGTH_PX = 16.0
# Host edges closer than this to the paste boundary are not reported as the host's.
_SEAM_MARGIN_PX = 2.0


# --------------------------------------------------------------------------- shapes


@dataclass(frozen=True, eq=False)
class ConvexPolygon:
    """A flat convex polygon; its sides are straight 3-D edges.

    Attributes
    ----------
    vertices : ndarray, shape (K, 2)
        Corners in undistorted normalised coordinates, counter-clockwise in
        the image (x right, y down), i.e. positive shoelace area.
    colour : ndarray, shape (3,)
        Linear RGB in [0, 1].
    texture : float
        Relative amplitude of the scene texture on this shape.
    """

    vertices: np.ndarray
    colour: np.ndarray
    texture: float = 0.02

    def _half_planes(self) -> tuple[np.ndarray, np.ndarray]:
        v = np.asarray(self.vertices, dtype=np.float64)
        e = np.roll(v, -1, axis=0) - v
        # Outward normals for positive shoelace area in a y-down frame.
        n = np.stack([e[:, 1], -e[:, 0]], axis=1) / np.hypot(e[:, 0], e[:, 1])[:, None]
        return n, np.einsum("ij,ij->i", n, v)

    def signed_distance(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance outside (>0) or inside (<0) and its unit gradient, normalised; exact near the sides."""
        n, d = self._half_planes()
        # Python floats keep float32 grids in float32.
        (nx0, ny0), *rest = n.tolist()
        sd = nx0 * x + ny0 * y - float(d[0])
        gx, gy = np.full_like(sd, nx0), np.full_like(sd, ny0)
        for (nx, ny), di in zip(rest, d[1:].tolist()):
            side = nx * x + ny * y - di
            nearer = side > sd
            sd = np.where(nearer, side, sd)
            gx[nearer], gy[nearer] = nx, ny
        return sd, gx, gy

    def boundary(self, samples: int = 128) -> np.ndarray:
        """Points along the outline, shape (K * samples, 2), normalised."""
        return np.concatenate(self.edges(samples))

    def edges(self, samples: int) -> list[np.ndarray]:
        """Each side sampled uniformly, a list of K arrays of shape (samples, 2)."""
        v = np.asarray(self.vertices, dtype=np.float64)
        t = np.linspace(0.0, 1.0, samples)[:, None]
        return [a + t * (b - a) for a, b in zip(v, np.roll(v, -1, axis=0))]


@dataclass(frozen=True, eq=False)
class Ring:
    """An annulus (a disc when ``inner == 0``): a curved distractor.

    Attributes
    ----------
    centre : ndarray, shape (2,)
        Undistorted normalised.
    outer, inner : float
        Radii, normalised.
    colour : ndarray, shape (3,)
    texture : float
    """

    centre: np.ndarray
    outer: float
    inner: float
    colour: np.ndarray
    texture: float = 0.02

    def signed_distance(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance outside (>0) or inside (<0) the annulus and its unit gradient, normalised."""
        dx, dy = x - float(self.centre[0]), y - float(self.centre[1])
        r = np.maximum(np.hypot(dx, dy), 1e-12)
        outer, inner = r - self.outer, self.inner - r
        sign = np.where(outer >= inner, 1.0, -1.0).astype(r.dtype)
        return np.maximum(outer, inner), sign * dx / r, sign * dy / r

    def boundary(self, samples: int = 256) -> np.ndarray:
        """Points on the outer circle, shape (samples, 2), normalised."""
        a = np.linspace(0.0, 2.0 * np.pi, samples)
        return self.centre + self.outer * np.stack([np.cos(a), np.sin(a)], axis=1)


@dataclass(frozen=True, eq=False)
class SineBand:
    """A cable ``y = y0 + amplitude * sin(2 pi x / wavelength + phase)``: a curved distractor.

    All lengths are undistorted normalised; ``half_width`` is half the
    thickness measured across the curve.
    """

    y0: float
    amplitude: float
    wavelength: float
    phase: float
    half_width: float
    colour: np.ndarray
    texture: float = 0.02

    def signed_distance(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance to the band (first order in the slope) and its unit gradient, normalised."""
        w = 2.0 * np.pi / self.wavelength
        arg = w * x + self.phase
        slope = self.amplitude * w * np.cos(arg)
        off = y - self.y0 - self.amplitude * np.sin(arg)
        length = np.sqrt(1.0 + slope * slope)
        sign = np.where(off >= 0, 1.0, -1.0).astype(off.dtype)
        return np.abs(off) / length - self.half_width, -sign * slope / length, sign / length

    def boundary(self, samples: int = 512) -> np.ndarray:
        """The band's two borders over x in [-3, 3], shape (2 * samples, 2)."""
        x = np.linspace(-3.0, 3.0, samples)
        yc = self.y0 + self.amplitude * np.sin(2.0 * np.pi * x / self.wavelength + self.phase)
        reach = self.half_width * np.sqrt(1.0 + (2.0 * np.pi * self.amplitude / self.wavelength) ** 2)
        return np.concatenate([np.stack([x, yc - reach], 1), np.stack([x, yc + reach], 1)])


Shape = ConvexPolygon | Ring | SineBand


@dataclass(frozen=True, eq=False)
class Scene:
    """A flat scene in undistorted normalised coordinates, drawn back to front.

    Attributes
    ----------
    background : ndarray, shape (3,)
        Wall colour, linear RGB in [0, 1].
    background_texture : float
        Relative texture amplitude of the wall.
    shapes : tuple of Shape
        Drawn in order over the wall.
    texture_seed : int
        Seed of the scene's texture field (fixed to the scene, not the camera,
        so two cameras see the same texture).
    """

    background: np.ndarray
    background_texture: float
    shapes: tuple[Shape, ...]
    texture_seed: int


@dataclass(frozen=True, eq=False)
class Capture:
    """A scene as one camera records it, before post-processing.

    Attributes
    ----------
    image : ndarray, shape (H, W, 3), float32
        Linear RGB in [0, 1], distorted and blurred.
    lines_px : list of ndarray, each (N_i, 2)
        The visible straight 3-D edges as distorted polylines, pixels.
    k1, k2 : float
    centre : tuple of float
        Centre of distortion, normalised.
    """

    image: np.ndarray
    lines_px: list[np.ndarray]
    k1: float
    k2: float
    centre: tuple[float, float]


@dataclass(frozen=True, eq=False)
class PasteTruth:
    """What was pasted, where from, and what it carries.

    Output pixels ``p`` of the region come from source pixels
    ``source_centre_px + (p - target_centre_px) / scale`` of the source
    capture (both in pixels of the unresized frame).

    Attributes
    ----------
    source_k1, source_k2 : float
        Distortion of the camera the pasted pixels come from (normalised
        coordinates of the source frame).
    scale : float
        Magnification applied to the pasted part (1 for copy-move and other camera).
    source_centre_px, target_centre_px : tuple of float
        Region centres in the source capture and in the output, pixels of the
        unresized frame.
    region_px : ndarray, shape (4, 2)
        Outline of the pasted region in output pixels (after any resize).
    lines_px : list of ndarray, each (N_i, 2)
        Straight 3-D edges inside the pasted part, output pixels (after any resize).
    source_lines_px : list of ndarray, each (N_i, 2)
        The same edges in pixels of the source capture; they are straight
        after undistortion with ``source_k1`` in the source frame.
    """

    source_k1: float
    source_k2: float
    scale: float
    source_centre_px: tuple[float, float]
    target_centre_px: tuple[float, float]
    region_px: np.ndarray
    lines_px: list[np.ndarray]
    source_lines_px: list[np.ndarray]


@dataclass(frozen=True, eq=False)
class SynthImage:
    """A synthetic photo with its truth.

    Attributes
    ----------
    image : ndarray, shape (H, W, 3), uint8
        Final pixels (JPEG-decoded when ``jpeg_bytes`` is set).
    jpeg_bytes : bytes or None
        The encoded file when a JPEG quality was set: what a user would analyse.
    mask : ndarray, shape (H, W), bool, or None
        True on pixels that received any pasted content; None when authentic.
    kind : str
        One of :data:`KINDS`.
    k1, k2 : float
        Host camera distortion (normalised coordinates).
    centre : tuple of float
        Host centre of distortion, normalised.
    pasted_k1 : float or None
        Distortion of the camera the pasted part comes from; None for
        authentic and copy-move (whose pasted part is the host's own, moved).
    lines_px : list of ndarray, each (N_i, 2)
        The host's visible straight 3-D edges as distorted polylines, pixels
        of the final image; for a splice, only the parts outside the mask.
    seed : int
    params : dict
        Flat JSON-able arguments that regenerate the image with :func:`generate`.
    paste : PasteTruth or None
    """

    image: np.ndarray
    jpeg_bytes: bytes | None
    mask: np.ndarray | None
    kind: str
    k1: float
    k2: float
    centre: tuple[float, float]
    pasted_k1: float | None
    lines_px: list[np.ndarray]
    seed: int
    params: dict = field(default_factory=dict)
    paste: PasteTruth | None = None


# --------------------------------------------------------------------------- scene generation


def _colour_near(rng: np.random.Generator, luma: float, low: float, high: float) -> np.ndarray:
    """A colour whose luminance differs from ``luma`` by a random amount in [low, high]."""
    diff = rng.choice([-1.0, 1.0]) * rng.uniform(low, high)
    if not 0.05 <= luma + diff <= 0.95:
        diff = -diff
    # Subtracting the tint's own luminance keeps the contrast exactly as drawn.
    tint = rng.uniform(-0.06, 0.06, 3)
    tint -= tint @ _LUMA
    return np.clip(np.clip(luma + diff, 0.05, 0.95) + tint, 0.0, 1.0)


def _quad(cx: float, cy: float, half_w: float, half_h: float, angle: float) -> np.ndarray:
    """Rotated rectangle, shape (4, 2), counter-clockwise in a y-down frame."""
    corners = np.array([[-half_w, -half_h], [half_w, -half_h], [half_w, half_h], [-half_w, half_h]])
    c, s = np.cos(angle), np.sin(angle)
    return corners @ np.array([[c, s], [-s, c]]) + [cx, cy]


def _band(y_left: float, y_right: float, below: bool) -> np.ndarray:
    """Half-plane beyond a tilted horizontal line, as a polygon reaching far outside the frame."""
    far = 3.0 if below else -3.0
    edge = [[-3.0, y_left], [3.0, y_right]]
    pts = np.array([edge[0], edge[1], [3.0, far], [-3.0, far]])
    return pts if below else pts[::-1]


def _room_shell(rng: np.random.Generator, ey: float, wall: float) -> list[Shape]:
    """Ceiling and floor edges far from the centre, and horizontal rails between."""
    shapes: list[Shape] = []
    if rng.random() < 0.75:
        y = -ey * rng.uniform(0.55, 0.85)
        tilt = rng.uniform(-0.03, 0.03)
        shapes.append(ConvexPolygon(_band(y - tilt, y + tilt, False), _colour_near(rng, wall, 0.1, 0.35), 0.01))
    if rng.random() < 0.85:
        y = ey * rng.uniform(0.45, 0.8)
        tilt = rng.uniform(-0.04, 0.04)
        shapes.append(ConvexPolygon(_band(y - tilt, y + tilt, True), _colour_near(rng, wall, 0.15, 0.45), 0.04))
    for _ in range(rng.integers(1, 3)):
        y, t, tilt = ey * rng.uniform(-0.7, 0.7), rng.uniform(0.006, 0.02), rng.uniform(-0.03, 0.03)
        top = np.array([[-3.0, y - tilt - t], [3.0, y + tilt - t]])
        verts = np.concatenate([top, top[::-1] + [0.0, 2.0 * t]])
        shapes.append(ConvexPolygon(verts, _colour_near(rng, wall, 0.08, 0.5), 0.01))
    return shapes


def _windows(rng: np.random.Generator, ex: float, ey: float, wall: float) -> list[Shape]:
    """Framed windows/panels, each at least a third of the frame height."""
    shapes: list[Shape] = []
    for _ in range(rng.integers(2, 5)):
        cx, cy = ex * rng.uniform(-0.85, 0.85), ey * rng.uniform(-0.35, 0.35)
        hw, hh = rng.uniform(0.06, 0.18), ey * rng.uniform(0.35, 0.6)
        angle = np.deg2rad(rng.uniform(-3.0, 3.0))
        frame = _colour_near(rng, wall, 0.1, 0.5)
        glass = _colour_near(rng, float(frame @ _LUMA), 0.1, 0.5)
        inset = rng.uniform(0.008, 0.025)
        shapes.append(ConvexPolygon(_quad(cx, cy, hw, hh, angle), frame, 0.015))
        shapes.append(ConvexPolygon(_quad(cx, cy, hw - inset, hh - inset, angle), glass, 0.03))
        if rng.random() < 0.5:
            shapes.append(ConvexPolygon(_quad(cx, cy, inset / 2.0, hh - inset, angle), frame, 0.015))
    return shapes


def _poles(rng: np.random.Generator, ex: float, wall: float) -> list[Shape]:
    """Full-height poles, one per stratum of the width, so every region of the frame has some."""
    n = int(rng.integers(4, 7))
    edges = np.linspace(-0.95 * ex, 0.95 * ex, n + 1)
    xs = rng.uniform(edges[:-1], edges[1:])
    shapes: list[Shape] = []
    for x in xs:
        half_w, angle = rng.uniform(0.006, 0.02), np.deg2rad(rng.uniform(-2.0, 2.0))
        shapes.append(ConvexPolygon(_quad(x, 0.0, half_w, 3.0, angle), _colour_near(rng, wall, 0.12, 0.55), 0.01))
    return shapes


def _distractors(rng: np.random.Generator, ex: float, ey: float, wall: float) -> list[Shape]:
    """Discs, rings and a cable: curved edges a line extractor must reject."""
    shapes: list[Shape] = []
    for _ in range(rng.integers(1, 4)):
        outer = rng.uniform(0.04, 0.16)
        inner = outer * rng.uniform(0.5, 0.9) if rng.random() < 0.5 else 0.0
        centre = np.array([ex * rng.uniform(-0.8, 0.8), ey * rng.uniform(-0.8, 0.8)])
        shapes.append(Ring(centre, outer, inner, _colour_near(rng, wall, 0.1, 0.5), 0.02))
    if rng.random() < 0.8:
        shapes.append(
            SineBand(
                y0=ey * rng.uniform(-0.6, 0.6),
                amplitude=rng.uniform(0.02, 0.08),
                wavelength=rng.uniform(0.4, 1.2),
                phase=rng.uniform(0.0, 2.0 * np.pi),
                half_width=rng.uniform(0.003, 0.008),
                colour=_colour_near(rng, wall, 0.2, 0.5),
            )
        )
    return shapes


def random_scene(rng: np.random.Generator, size: tuple[int, int], wall: np.ndarray | None = None) -> Scene:
    """A room or facade with long straight edges in every part of the frame.

    Parameters
    ----------
    rng : numpy.random.Generator
    size : (int, int)
        Frame ``(W, H)`` in pixels; only its aspect ratio matters.
    wall : ndarray, shape (3,), optional
        Wall colour; drawn from ``rng`` when omitted (a donor scene reuses the
        host's so the pasted background matches, as a forger would choose).

    Returns
    -------
    Scene
        Ceiling and floor edges, 1-2 rails, 2-4 framed windows at least a
        third of the frame height, 4-6 full-height poles spread over the
        width, and 1-3 rings plus usually a sinusoidal cable as distractors.
    """
    w, h = size
    ex, ey = w / max(w, h), h / max(w, h)
    wall = np.clip(rng.uniform(0.35, 0.65) + rng.uniform(-0.05, 0.05, 3), 0, 1) if wall is None else wall
    luma = float(wall @ _LUMA)
    shapes = [
        *_room_shell(rng, ey, luma),
        *_windows(rng, ex, ey, luma),
        *_poles(rng, ex, luma),
        *_distractors(rng, ex, ey, luma),
    ]
    return Scene(wall, 0.03, tuple(shapes), int(rng.integers(2**31)))


# --------------------------------------------------------------------------- rendering


@dataclass(frozen=True, eq=False)
class _LensGrid:
    """Where each distorted pixel looks in the scene, and the local Jacobian of that map.

    With ``d = p_d - c`` (normalised) the model ``p_u = c + d (1 + k1 r^2 + k2 r^4)``
    (paper eqs. 4-5) has the symmetric Jacobian ``a I + b d d^T`` with
    ``a = 1 + k1 r^2 + k2 r^4`` and ``b = 2 k1 + 4 k2 r^2``. All arrays are
    (H, W) float32.
    """

    ux: np.ndarray
    uy: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    a: np.ndarray
    b: np.ndarray
    scale: float

    @classmethod
    def build(cls, shape: tuple[int, int], k1: float, k2: float, centre) -> _LensGrid:
        h, w = shape
        xs, ys = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
        pts = to_normalised(np.stack([xs.ravel(), ys.ravel()], axis=1), shape)
        u = undistort(pts, k1, k2, centre)
        d = pts - np.asarray(centre, dtype=np.float64)
        r2 = np.einsum("ij,ij->i", d, d)
        a = 1.0 + k1 * r2 + k2 * r2 * r2
        b = 2.0 * k1 + 4.0 * k2 * r2
        grids = (v.reshape(h, w).astype(np.float32) for v in (u[:, 0], u[:, 1], d[:, 0], d[:, 1], a, b))
        return cls(*grids, scale=norm_scale(shape))

    def coverage(self, obj: Shape, rows: slice, cols: slice) -> np.ndarray:
        """Fraction of each pixel of the box that ``obj`` covers, (h, w) float32.

        The signed distance is carried to distorted pixels by the Jacobian
        (chain rule: the pixel-space gradient is ``J g / scale``), then the
        pixel square's area on the inner side of that straight edge is exact.
        """
        sd, gx, gy = obj.signed_distance(self.ux[rows, cols], self.uy[rows, cols])
        dx, dy, a, b = self.dx[rows, cols], self.dy[rows, cols], self.a[rows, cols], self.b[rows, cols]
        along = b * (dx * gx + dy * gy)
        jx, jy = a * gx + along * dx, a * gy + along * dy
        norm = np.maximum(np.hypot(jx, jy), 1e-12)
        return _square_coverage(-sd * np.float32(self.scale) / norm, np.abs(jx) / norm, np.abs(jy) / norm)


def _square_coverage(inside: np.ndarray, nx: np.ndarray, ny: np.ndarray) -> np.ndarray:
    """Area of a unit pixel on the inner side of a straight edge.

    Parameters
    ----------
    inside : ndarray
        Signed distance of the pixel centre into the shape, pixels.
    nx, ny : ndarray
        Absolute components of the edge's unit normal.

    Notes
    -----
    The normal's projection of a point uniform on the pixel is the sum of two
    uniforms of widths ``nx`` and ``ny``; its trapezoidal density integrates to
    a piecewise quadratic ramp. This is the box-filtered step, so the edge
    keeps its exact sub-pixel position at every phase and orientation.
    """
    p, q = np.minimum(nx, ny), np.maximum(nx, ny)
    s = np.clip(inside + 0.5 * (p + q), 0.0, p + q)
    pq2 = 2.0 * np.maximum(p, 1e-6) * q
    middle = (s - 0.5 * p) / q
    return np.where(s < p, s * s / pq2, np.where(s > q, 1.0 - (p + q - s) ** 2 / pq2, middle))


def _pixel_box(shape_obj: Shape, shape: tuple[int, int], k1: float, k2: float, centre) -> tuple[slice, slice]:
    """Rows and columns a shape can touch in the distorted frame (3 px margin)."""
    pts = distort(shape_obj.boundary(), k1, k2, centre)
    h, w = shape
    if not np.all(np.isfinite(pts)):
        # Part of the outline lies beyond the fold of a pincushion model: the
        # outline no longer bounds the image of the shape, so take the frame.
        return slice(0, h), slice(0, w)
    px = to_pixels(pts, shape)
    lo = np.floor(px.min(axis=0) - 3.0).astype(int)
    hi = np.ceil(px.max(axis=0) + 4.0).astype(int)
    return slice(max(lo[1], 0), min(hi[1], h)), slice(max(lo[0], 0), min(hi[0], w))


def _texture(scene: Scene, ux: np.ndarray, uy: np.ndarray) -> np.ndarray:
    """Zero-mean value noise fixed to the scene, two octaves, sampled at ``(ux, uy)``; (H, W) float32."""
    rng = np.random.default_rng(scene.texture_seed)
    out = np.zeros(ux.shape, dtype=np.float32)
    for spacing in _TEXTURE_SPACINGS:
        n = int(np.ceil(2.0 * _TEXTURE_EXTENT / spacing)) + 1
        grid = rng.standard_normal((n, n)).astype(np.float32)
        coords = [(uy + _TEXTURE_EXTENT) / spacing, (ux + _TEXTURE_EXTENT) / spacing]
        out += ndimage.map_coordinates(grid, coords, order=1, mode="nearest") * 0.5
    return out


def render_scene(
    scene: Scene,
    size: tuple[int, int],
    k1: float,
    k2: float = 0.0,
    centre: Sequence[float] = (0.0, 0.0),
    blur: float = 0.7,
) -> Capture:
    """Photograph a scene through a radially distorting lens.

    Parameters
    ----------
    scene : Scene
    size : (int, int)
        ``(W, H)`` in pixels.
    k1, k2 : float
        Radial coefficients of the model ``p_u = c + (p_d - c)(1 + k1 r^2 + k2 r^4)``
        (paper eq. 1), normalised coordinates; ``k1 > 0`` is barrel.
    centre : (float, float)
        Centre of distortion ``c``, normalised.
    blur : float
        Standard deviation of the Gaussian optics blur, pixels (0 for none).

    Returns
    -------
    Capture
        The (H, W, 3) float32 image and the truth polylines of its straight edges.
    """
    w, h = size
    shape = (h, w)
    centre = (float(centre[0]), float(centre[1]))
    grid = _LensGrid.build(shape, k1, k2, centre)
    colour = np.empty((h, w, 3), dtype=np.float32)
    colour[...] = scene.background
    amplitude = np.full((h, w), scene.background_texture, dtype=np.float32)
    for obj in scene.shapes:
        rows, cols = _pixel_box(obj, shape, k1, k2, centre)
        cover = grid.coverage(obj, rows, cols)
        colour[rows, cols] += cover[..., None] * (np.asarray(obj.colour, np.float32) - colour[rows, cols])
        amplitude[rows, cols] += cover * (np.float32(obj.texture) - amplitude[rows, cols])
    image = colour * (1.0 + amplitude * _texture(scene, grid.ux, grid.uy))[..., None]
    if blur > 0:
        image = ndimage.gaussian_filter(image, sigma=(blur, blur, 0.0), mode="nearest")
    return Capture(np.clip(image, 0.0, 1.0), _truth_lines(scene, shape, k1, k2, centre), k1, k2, centre)


def _luminance_at(scene: Scene, pts: np.ndarray) -> np.ndarray:
    """Untextured scene luminance at undistorted normalised points (N, 2), hard edges."""
    luma = np.full(len(pts), float(scene.background @ _LUMA))
    for obj in scene.shapes:
        inside = obj.signed_distance(pts[:, 0], pts[:, 1])[0] < 0
        luma[inside] = float(np.asarray(obj.colour) @ _LUMA)
    return luma


def _runs(points: np.ndarray, keep: np.ndarray, group: np.ndarray, min_length: float) -> list[np.ndarray]:
    """Split polylines into maximal runs of kept points within one group.

    Parameters
    ----------
    points : ndarray, shape (N, 2)
    keep : ndarray, shape (N,), bool
    group : ndarray, shape (N,), int
        Polyline each point belongs to; points of a group are consecutive.
    min_length : float
        Runs whose chord is shorter are dropped, same units as ``points``.
    """
    breaks = np.flatnonzero((np.diff(keep.astype(np.int8)) != 0) | (np.diff(group) != 0)) + 1
    pieces = zip(np.split(points, breaks), np.split(keep, breaks))
    return [p for p, k in pieces if k[0] and np.hypot(*(p[-1] - p[0])) >= min_length]


def _sample_sides(scene: Scene, scale: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points every ``_TRUTH_STEP_PX`` along each polygon side, undistorted normalised.

    Returns the points (N, 2), the index of the side each belongs to (N,) and
    the side's unit normal at each point (N, 2).
    """
    sides = [side for obj in scene.shapes if isinstance(obj, ConvexPolygon) for side in obj.edges(2)]
    counts = [max(int(np.hypot(*(b - a)) * scale / _TRUTH_STEP_PX), 2) for a, b in sides]
    points = np.concatenate([a + np.linspace(0.0, 1.0, n)[:, None] * (b - a) for (a, b), n in zip(sides, counts)])
    normals = np.array([[a[1] - b[1], b[0] - a[0]] for a, b in sides]) / np.array(
        [np.hypot(*(b - a)) for a, b in sides]
    )[:, None]
    group = np.repeat(np.arange(len(sides)), counts)
    return points, group, normals[group]


def _truth_lines(scene: Scene, shape: tuple[int, int], k1: float, k2: float, centre) -> list[np.ndarray]:
    """Visible pieces of the scene's straight edges as distorted polylines, pixels.

    An edge point counts as visible when it lies in the frame and the scene's
    luminance differs by at least ``_MIN_CONTRAST`` a pixel and a half either
    side of it, which removes occluded parts and sides against a like colour.
    The polylines are exact images of straight lines under the model: they
    come from :func:`.geometry.distort`, the inverse of the renderer's map.
    """
    if not any(isinstance(obj, ConvexPolygon) for obj in scene.shapes):
        return []
    scale = norm_scale(shape)
    u, group, normal = _sample_sides(scene, scale)
    d = distort(u, k1, k2, centre)
    px = to_pixels(d, shape)
    finite = np.all(np.isfinite(px), axis=1)
    h, w = shape
    with np.errstate(invalid="ignore"):
        in_frame = finite & np.all((px >= 0.5) & (px <= [w - 1.5, h - 1.5]), axis=1)
    r2 = np.sum((np.where(finite[:, None], d, 0.0) - centre) ** 2, axis=1)
    # A distorted pixel spans about (1 + k1 r^2 + k2 r^4) / scale undistorted units.
    offset = (_CONTRAST_OFFSET_PX * np.abs(1.0 + k1 * r2 + k2 * r2 * r2) / scale)[:, None] * normal
    contrast = np.abs(_luminance_at(scene, u + offset) - _luminance_at(scene, u - offset))
    return _runs(px, in_frame & (contrast >= _MIN_CONTRAST), group, _MIN_TRUTH_LENGTH_PX)


# --------------------------------------------------------------------------- post-processing


@dataclass(frozen=True)
class _Post:
    noise: float
    jpeg_quality: int | None
    resize: float | None


def _add_noise(image: np.ndarray, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """Gaussian sensor noise (sigma in units of full scale), quantised to uint8."""
    noisy = image + sigma * rng.standard_normal(image.shape, dtype=np.float32)
    return np.round(np.clip(noisy, 0.0, 1.0) * 255.0).astype(np.uint8)


def _resized_shape(shape: tuple[int, int], factor: float | None) -> tuple[int, int]:
    if factor is None or factor == 1.0:
        return shape
    return max(int(round(shape[0] * factor)), 1), max(int(round(shape[1] * factor)), 1)


def _resize_points(points: np.ndarray, shape_in: tuple[int, int], shape_out: tuple[int, int]) -> np.ndarray:
    """Pixel-centre coordinates under a resize that maps pixel edges onto pixel edges (Pillow's convention)."""
    factor = np.array([shape_out[1] / shape_in[1], shape_out[0] / shape_in[0]])
    return (np.asarray(points) + 0.5) * factor - 0.5


def _finish(
    image: np.ndarray, alpha: np.ndarray | None, post: _Post, rng: np.random.Generator
) -> tuple[np.ndarray, bytes | None, np.ndarray | None]:
    """Noise, resize and JPEG, identical for authentic and spliced images.

    Returns the final (H', W', 3) uint8 pixels, the JPEG file (or None) and
    the (H', W') bool mask of pixels with any pasted content (or None).
    """
    pixels = _add_noise(image, post.noise, rng)
    out_shape = _resized_shape(pixels.shape[:2], post.resize)
    mask = None if alpha is None else alpha > 0
    if out_shape != pixels.shape[:2]:
        size = (out_shape[1], out_shape[0])
        pixels = np.asarray(Image.fromarray(pixels).resize(size, Image.Resampling.LANCZOS))
        if alpha is not None:
            resized = Image.fromarray(alpha.astype(np.float32), "F").resize(size, Image.Resampling.BILINEAR)
            mask = np.asarray(resized) > 1e-3
    if post.jpeg_quality is None:
        return pixels, None, mask
    buffer = io.BytesIO()
    Image.fromarray(pixels).save(buffer, format="JPEG", quality=int(post.jpeg_quality))
    data = buffer.getvalue()
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB")), data, mask


# --------------------------------------------------------------------------- authentic


def _streams(seed: int) -> tuple[np.random.Generator, np.random.Generator, np.random.SeedSequence]:
    """Independent host-scene, noise and splice streams.

    Keeping them apart lets a splice share its host scene and its noise with
    the authentic image of the same seed.
    """
    host, noise, splice = np.random.SeedSequence(seed).spawn(3)
    return np.random.default_rng(host), np.random.default_rng(noise), splice


def _params(kind: str, seed: int, size, k1, k2, centre, noise, blur, jpeg_quality, resize, feather_px=None) -> dict:
    params = {
        "kind": kind, "seed": int(seed), "size": [int(size[0]), int(size[1])], "k1": float(k1), "k2": float(k2),
        "centre": [float(centre[0]), float(centre[1])], "noise": float(noise), "blur": float(blur),
        "jpeg_quality": None if jpeg_quality is None else int(jpeg_quality),
        "resize": None if resize is None else float(resize),
    }
    if feather_px is not None:
        params["feather_px"] = float(feather_px)
    return params


def render_authentic(
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
) -> SynthImage:
    """An authentic photo of a random scene.

    Parameters
    ----------
    seed : int
        Determines scene and noise; equal arguments give identical bytes.
    size : (int, int)
        ``(W, H)`` of the camera frame, pixels.
    k1, k2 : float
        Radial distortion (paper eq. 1), normalised coordinates.
    centre : (float, float)
        Centre of distortion, normalised.
    noise : float
        Standard deviation of Gaussian noise, fraction of full scale.
    blur : float
        Optics blur (Gaussian sigma), pixels.
    jpeg_quality : int or None
        Pillow JPEG quality; None keeps the lossless pixels.
    resize : float or None
        Final rescale factor (Lanczos) applied before JPEG.

    Returns
    -------
    SynthImage
    """
    host_rng, noise_rng, _ = _streams(seed)
    capture = render_scene(random_scene(host_rng, size), size, k1, k2, centre, blur)
    post = _Post(noise, jpeg_quality, resize)
    pixels, data, _ = _finish(capture.image, None, post, noise_rng)
    shape_in = (size[1], size[0])
    return SynthImage(
        image=pixels,
        jpeg_bytes=data,
        mask=None,
        kind="authentic",
        k1=float(k1),
        k2=float(k2),
        centre=capture.centre,
        pasted_k1=None,
        lines_px=[_resize_points(p, shape_in, pixels.shape[:2]) for p in capture.lines_px],
        seed=int(seed),
        params=_params("authentic", seed, size, k1, k2, centre, noise, blur, jpeg_quality, resize),
    )


# --------------------------------------------------------------------------- splices


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
    return _runs(pts, keep, group, min_length)


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
        pasted = _clip_lines(moved, placement.region, True, feather + 1.0, _MIN_TRUTH_LENGTH_PX)
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
    host_rng, noise_rng, splice_seq = _streams(seed)
    scene = random_scene(host_rng, size)
    host = render_scene(scene, size, k1, k2, centre, blur)
    shape = (size[1], size[0])
    found = _source_and_placement(kind, scene, host, size, blur, splice_seq, feather_px)
    source, placement, pasted, source_lines = found
    alpha = _alpha(shape, placement.region, feather_px)
    spliced = _transplant(host.image, source.image, placement, alpha)
    pixels, data, mask = _finish(spliced, alpha, _Post(noise, jpeg_quality, resize), noise_rng)
    out_shape = pixels.shape[:2]
    host_lines = _clip_lines(host.lines_px, placement.region, False, _SEAM_MARGIN_PX, _MIN_TRUTH_LENGTH_PX)
    paste = PasteTruth(
        source_k1=float(source.k1),
        source_k2=float(source.k2),
        scale=float(placement.scale),
        source_centre_px=(float(placement.source_centre[0]), float(placement.source_centre[1])),
        target_centre_px=(float(placement.target_centre[0]), float(placement.target_centre[1])),
        region_px=_resize_points(placement.region, shape, out_shape),
        lines_px=[_resize_points(p, shape, out_shape) for p in pasted],
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
        lines_px=[_resize_points(p, shape, out_shape) for p in host_lines],
        seed=int(seed),
        params=_params(kind, seed, size, k1, k2, centre, noise, blur, jpeg_quality, resize, feather_px),
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


# --------------------------------------------------------------------------- files and command line


def _polylines_json(lines: list[np.ndarray]) -> list[list[list[float]]]:
    # 1e-4 px is far below any detector's precision and keeps the files small.
    return [np.round(p, 4).tolist() for p in lines]


def truth_record(img: SynthImage) -> dict:
    """JSON-able truth of one image: camera, splice and the straight edges."""
    record = {
        "kind": img.kind,
        "seed": img.seed,
        "k1": img.k1,
        "k2": img.k2,
        "centre": list(img.centre),
        "pasted_k1": img.pasted_k1,
        "size": [int(img.image.shape[1]), int(img.image.shape[0])],
        "params": img.params,
        "lines_px": _polylines_json(img.lines_px),
    }
    if img.paste is not None:
        p = img.paste
        record["paste"] = {
            "source_k1": p.source_k1,
            "source_k2": p.source_k2,
            "scale": p.scale,
            "source_centre_px": list(p.source_centre_px),
            "target_centre_px": list(p.target_centre_px),
            "region_px": np.round(p.region_px, 4).tolist(),
            "lines_px": _polylines_json(p.lines_px),
            "source_lines_px": _polylines_json(p.source_lines_px),
        }
    return record


def write(img: SynthImage, out_dir: Path, stem: str) -> list[Path]:
    """Write the photo, its mask and its truth.

    The photo is ``stem.jpg`` (the encoded bytes) or, without JPEG, the
    lossless ``stem.png``; the mask ``stem_mask.png`` (255 on pasted pixels);
    the truth ``stem.json`` (:func:`truth_record`).

    Returns
    -------
    list of Path
        Photo, mask (splices only) and truth files, in that order.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if img.jpeg_bytes is not None:
        photo = out_dir / f"{stem}.jpg"
        photo.write_bytes(img.jpeg_bytes)
    else:
        photo = out_dir / f"{stem}.png"
        Image.fromarray(img.image).save(photo)
    paths = [photo]
    if img.mask is not None:
        mask_path = out_dir / f"{stem}_mask.png"
        Image.fromarray(img.mask.astype(np.uint8) * 255).save(mask_path)
        paths.append(mask_path)
    truth = out_dir / f"{stem}.json"
    truth.write_text(json.dumps(truth_record(img), separators=(",", ":"), sort_keys=True) + "\n")
    paths.append(truth)
    return paths


# --------------------------------------------------------------------------- validation cases

_CASE_SIZES = ((1200, 900), (1600, 1200))
_CASE_QUALITIES = (75, 85, 95)


def validation_cases(seed: int, count: int) -> Iterator[SyntheticCase]:
    """``count`` authentic and ``count`` spliced photos for ``forensics validate``.

    Each case draws its host lens (``|k1|`` in [0.03, 0.15], either sign),
    size and JPEG quality from ``(seed, i)``; splices cycle through the
    paper's three kinds. Conditions: ``kind``, ``jpeg_quality``, ``size``.
    """
    for i in range(count):
        for spliced in (False, True):
            rng = np.random.default_rng([seed, i, int(spliced)])
            k1 = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.03, 0.15))
            size = _CASE_SIZES[int(rng.integers(len(_CASE_SIZES)))]
            quality = int(_CASE_QUALITIES[int(rng.integers(len(_CASE_QUALITIES)))])
            kind = SPLICE_KINDS[i % len(SPLICE_KINDS)] if spliced else "authentic"
            case_seed = int(rng.integers(2**31))
            img = make_splice(kind, case_seed, size=size, k1=k1, jpeg_quality=quality)
            yield SyntheticCase(
                name=f"lens-{kind.replace('_', '-')}-{i:03d}",
                data=img.jpeg_bytes,
                suffix=".jpg",
                spliced=spliced,
                mask=img.mask,
                conditions={"kind": kind if spliced else "none", "jpeg_quality": str(quality),
                            "size": f"{size[0]}x{size[1]}"},
            )
