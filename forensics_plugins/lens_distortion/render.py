"""Photographing a scene (:mod:`.scene`) through a radially distorting lens, with the truth of its straight edges.

A camera renders the scene through the paper's radial model (eqs. 1-5): every
distorted pixel ``p_d`` shows the scene at ``p_u = undistort(p_d)``, which is
closed form, so no inverse is needed. Anti-aliasing is analytic rather than by
supersampling: each shape's signed distance is carried into distorted pixels
through the model's Jacobian and turned into the exact area of the pixel
square on its inner side, so edges keep their true sub-pixel curve (measured
error about 1e-4 px). Optics blur follows; :mod:`.photo` adds the sensor and
the file.

The truth is the visible pieces of the scene's straight edges, traced as
distorted polylines in pixels.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from .geometry import distort, norm_scale, to_normalised, to_pixels, undistort
from .scene import ConvexPolygon, Scene, Shape

#: Truth polylines whose chord is shorter than this, in pixels, are dropped.
MIN_TRUTH_LENGTH_PX = 16.0

# Half-side of the square, in undistorted normalised units, that the texture
# covers: the frame corners undistort to r_u <= 1.9 for k1 <= 0.3.
_TEXTURE_EXTENT = 2.5
_TEXTURE_SPACINGS = (0.04, 0.01)
# Parameter step of the truth polylines, in pixels of the host image.
_TRUTH_STEP_PX = 2.0
# Distance either side of an edge, in pixels, at which its contrast is judged.
_CONTRAST_OFFSET_PX = 1.5
_MIN_CONTRAST = 0.04


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


def polyline_runs(points: np.ndarray, keep: np.ndarray, group: np.ndarray, min_length: float) -> list[np.ndarray]:
    """Split polylines into maximal runs of kept points within one group.

    Parameters
    ----------
    points : ndarray, shape (N, 2)
    keep : ndarray, shape (N,), bool
    group : ndarray, shape (N,), int
        Polyline each point belongs to; points of a group are consecutive.
    min_length : float
        Runs whose chord is shorter are dropped, same units as ``points``.

    Returns
    -------
    list of ndarray, each (N_i, 2)
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
    contrast = np.abs(scene.luminance(u + offset) - scene.luminance(u - offset))
    return polyline_runs(px, in_frame & (contrast >= _MIN_CONTRAST), group, MIN_TRUTH_LENGTH_PX)
