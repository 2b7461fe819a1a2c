"""The scene model of the synthetic photos: flat shapes over a textured wall, and random rooms.

A scene is a painter's list of flat shapes (convex polygons for walls, floors,
windows, poles and rails; rings and a sinusoidal cable as curved distractors)
over a textured wall, defined in *undistorted normalised* coordinates (see
:mod:`.geometry`). The sides of the polygons are the straight 3-D edges whose
bowing the detector measures; :mod:`.render` photographs a scene through a lens.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_LUMA = np.array([0.299, 0.587, 0.114])


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

    def luminance(self, pts: np.ndarray) -> np.ndarray:
        """Untextured luminance at undistorted normalised points (N, 2), hard edges."""
        luma = np.full(len(pts), float(self.background @ _LUMA))
        for obj in self.shapes:
            inside = obj.signed_distance(pts[:, 0], pts[:, 1])[0] < 0
            luma[inside] = float(np.asarray(obj.colour) @ _LUMA)
        return luma


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
