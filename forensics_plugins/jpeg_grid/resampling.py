"""Regions whose grid one radial warp of the whole photo explains: lens correction, not a paste.

A photo compressed once, then resampled by a radial warp about its centre
(lens correction in an editor or a camera app) and saved again at high
quality keeps the first compression's block grid where the warp is close to
the identity. At distance ``r`` from the centre the warp moves the pixels
by ``D(r)`` along the radius, so the old grid survives shifted by ``D(r)
u`` rounded to whole pixels, ``u`` the unit vector from the centre: ZERO
then finds regions voting for the main grid shifted by one pixel outwards
(or inwards) in a band where ``|D|`` nears one, by two further out, and so
on, each region's shift pointing along its own radius. A pasted piece's
grid is shifted by whatever the forger's placement made it, one of 63
offsets, unrelated to where it lies.

A lens correction's displacement is, to first order, ``D(r) = a (r /
R)^3 + b (r / R)`` (the one-term radial model, paper eqs. 1-5, and the
zoom an editor adds to fill the frame; ``R`` the half diagonal), and a grid
only shows it modulo 8: a shift of (8, 1) px reads as (0, 1). So a region is explained by the warp when one representative of
its grid's shift modulo 8 (``s + 8 (i, j)``) lies along the radius through
its centre, within ``PERP_TOL`` pixels (rounding each coordinate moves it
by at most 0.5, and the region spans a range of directions), with a length
within ``PROFILE_TOL`` (or a share ``PROFILE_REL`` of ``D``, for the higher
terms of real corrections, at most ``PROFILE_MAX_TOL``) of ``D`` at its
distance. ``(a, b)`` is the
profile that explains the most regions, found from pairs of the strongest
regions (two regions fix it) and checked on all. A paste matches a given profile at its place by chance in a few
per cent of placements where ``D`` is a few pixels (about 4 of the 64
shifts modulo 8), up to about a fifth far out where it is tens of pixels
(the tolerance then covers 12 of the 64), and two
regions fit some profile always, so the warp is named only when at least
``MIN_REGIONS`` regions in directions at least ``MIN_SPREAD_DEG`` apart fit
one profile, and regions it does not explain
stay foreign: a piece pasted into a lens-corrected photo is still
reported.

The old grid survives best in one band of distances, where the shift is
near whole pixels and the interpolation blurs least, and at quality 100
(where the file's own compression leaves few zeros) the band's regions can
outvote the main grid. So the seeds are the strongest regions and the
strongest of each tenth of the half diagonal; each seed also proposes the
one-term profiles through it; the chosen profile is refitted by least
squares to the shifts it explains while that explains more; and the first
grid's origin is the main grid's or, in a JPEG file, the file's own (0, 0),
whichever explains more. Once a warp is established, its profile is
refitted on sample pixels of every region and each region is judged pixel
by pixel (:func:`field_explained`): where the shift is several pixels, a
region's centre lies up to a pixel off the radius and the fit on centres
misses by a few pixels far out, while the field it predicts matches a
nearest-neighbour correction's patches throughout. Allowing more (half-pixel origins for editors that
truncate, a tolerance growing with a region's angular width) explained one
more nearest-neighbour correction in 58 but five of 34 pieces pasted into
lens-corrected photos, and was left out.

References
----------
.. [1] T. Nikoukhah, J. Anger, M. Colom, J.-M. Morel, R. Grompone von Gioi,
   ZERO: a local JPEG grid origin detector based on the number of DCT zeros
   and its applications in image forensics, IPOL 11 (2021).
.. [2] H. R. Chennamma, L. Rangarajan, Image splicing detection using
   inherent lens radial distortion, IJCSI 7(6), 2010 (the radial model).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations

import numpy as np

from .regions import Region
from .votes import grid_origin

PERP_TOL = 1.0
PROFILE_TOL = 1.0
PROFILE_REL = 0.15
#: Beyond a few pixels the shift's representatives modulo 8 crowd every length: the tolerance stops here.
PROFILE_MAX_TOL = 3.0
MIN_REGIONS = 3
#: Once a warp is established, a region whose grid it predicts at this share of the region's pixels is explained.
MIN_FIELD_SHARE = 0.5
#: Pixels of each region on which the established warp is refitted and judged.
FIELD_SAMPLES = 64
MIN_SPREAD_DEG = 60.0
#: Profiles searched: |D| at the half diagonal and |b| at most this many pixels, beyond any editor's correction.
MAX_SHIFT_PX = 400.0
#: The strongest regions whose pairs propose profiles (each pair fixes one per pair of shift representatives).
SEED_REGIONS = 24
#: Distance bands (of the half diagonal) each giving seeds beside the strongest regions, and seeds per band.
_RADIUS_BINS = 10
_SEEDS_PER_BIN = 2
#: Least-squares refits of the chosen profile to the shifts it explains.
_REFITS = 3
#: The profiles best supported by the seeds that are then judged on every region.
_FINALISTS = 50
#: Two regions closer in distance than this share of the half diagonal cannot separate the two terms.
MIN_RADIUS_GAP = 0.05
#: Share of a region box's middle points at which one radial move, rounded, must give the region's shift.
STEP_MIN_SHARE = 0.6
#: Points per side of a region box's middle half, and radial moves (pixels), over which a one-pixel step is rounded.
_STEP_SAMPLES = 5
_STEP_LENGTHS = np.linspace(0.5, 1.5, 11)
#: Representatives of a shift modulo 8 within this many periods of it.
_WRAPS = np.array([(i, j) for i in range(-6, 7) for j in range(-6, 7)], dtype=np.float64)


@dataclass(frozen=True)
class RadialWarp:
    """A radial resampling of the whole photo after its first compression.

    Attributes
    ----------
    terms : tuple of float
        ``(a, b)`` of the profile ``D(r) = a (r / R)^3 + b (r / R)``, pixels.
    at_corner_px : float
        ``D(R)``, pixels: positive when the warp pushed pixels outwards.
    explained : tuple of int
        Indices (into the regions given) of the regions it explains.
    profile : tuple of (float, float)
        For each explained region, in order of distance: its distance from
        the centre and its grid's shift along the radius, pixels (the
        correction's displacement sampled where the old grid shows it).
    origin : tuple of int
        The first compression's grid origin ``(dx, dy)`` where the warp is
        the identity.
    """

    terms: tuple[float, float]
    at_corner_px: float
    explained: tuple[int, ...]
    profile: tuple[tuple[float, float], ...]
    origin: tuple[int, int] = (0, 0)


@dataclass(frozen=True)
class _Place:
    index: int
    rho: float  # distance from the centre / half diagonal
    angle: float
    lengths: np.ndarray  # (k,) signed radial lengths of the shift's representatives, pixels


def _radial_lengths(region: Region, main_origin: tuple[int, int], u: np.ndarray) -> np.ndarray:
    """Signed lengths along ``u`` of the region's shift representatives that lie along its radius, shape (k,)."""
    dx, dy = grid_origin(region.grid)
    shift = np.array([(dx - main_origin[0]) % 8, (dy - main_origin[1]) % 8], dtype=np.float64)
    candidates = shift[None, :] + 8.0 * _WRAPS
    perp = np.abs(candidates @ np.array([-u[1], u[0]]))
    return (candidates @ u)[perp <= PERP_TOL]


def _fits(lengths: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """Whether a representative lies within the tolerance of the expected shift, broadcast."""
    tolerance = np.clip(PROFILE_REL * np.abs(expected), PROFILE_TOL, PROFILE_MAX_TOL)
    return (np.abs(lengths - expected) <= tolerance) & (np.abs(expected) >= 0.5)


def _profiles(seeds: list[_Place]) -> np.ndarray:
    """Every profile ``(a, b)`` two seed regions and one representative of each fix, shape (n, 2).

    The old grid survives best in a band of distances (where the shift is
    near whole pixels and the interpolation blurs least), and regions in one
    band cannot separate the two terms: each seed's representative also
    proposes the one-term profiles through it, ``(L / rho^3, 0)`` and ``(0, L
    / rho)``.
    """
    out = [np.column_stack((p.lengths / p.rho**3, np.zeros(p.lengths.size))) for p in seeds]
    out += [np.column_stack((np.zeros(p.lengths.size), p.lengths / p.rho)) for p in seeds]
    for p, q in combinations(seeds, 2):
        if abs(p.rho - q.rho) < MIN_RADIUS_GAP or not (p.lengths.size and q.lengths.size):
            continue
        lp, lq = (x.ravel() for x in np.meshgrid(p.lengths, q.lengths))
        system = np.array([[p.rho**3, p.rho], [q.rho**3, q.rho]])
        out.append(np.linalg.solve(system, np.vstack((lp, lq))).T)
    ab = np.vstack(out) if out else np.zeros((0, 2))
    return ab[(np.abs(ab.sum(axis=1)) <= MAX_SHIFT_PX) & (np.abs(ab[:, 1]) <= MAX_SHIFT_PX)]


def _explained(places: list[_Place], a: float, b: float) -> list[tuple[float, float, int, float]]:
    """The places the profile explains: (distance share, radial shift, index, angle) each."""
    out = []
    for p in places:
        expected = a * p.rho**3 + b * p.rho
        ok = _fits(p.lengths, expected)
        if ok.any():
            best = p.lengths[ok][np.argmin(np.abs(p.lengths[ok] - expected))]
            out.append((p.rho, float(best), p.index, p.angle))
    return out


def _refined(places: list[_Place], a: float, b: float) -> tuple[float, float, list[tuple[float, float, int, float]]]:
    """The profile refitted by least squares to the shifts it explains while that explains more, and its matches.

    Seeds in one band fix the profile there only; the refit carries it to
    the regions further in and out that it then also explains.
    """
    matched = sorted(_explained(places, a, b))
    for _ in range(_REFITS):
        rho, shift = (np.array([m[i] for m in matched]) for i in (0, 1))
        (a2, b2), *_ = np.linalg.lstsq(np.column_stack((rho**3, rho)), shift, rcond=None)
        again = sorted(_explained(places, float(a2), float(b2)))
        if len(again) <= len(matched):
            break
        a, b, matched = float(a2), float(b2), again
    return a, b, matched


def _seeds(places: list[_Place]) -> list[_Place]:
    """The strongest places, and the strongest few at each distance, so that pairs of seeds span the radius."""
    seeds = places[:SEED_REGIONS]
    chosen = {p.index for p in seeds}
    bins = np.minimum((np.array([p.rho for p in places]) * _RADIUS_BINS).astype(int), _RADIUS_BINS - 1)
    for k in range(_RADIUS_BINS):
        extra = [p for p, b in zip(places, bins) if b == k and p.index not in chosen][:_SEEDS_PER_BIN]
        seeds += extra
        chosen.update(p.index for p in extra)
    return seeds


def _spread_deg(angles: np.ndarray) -> float:
    return float(np.degrees(np.abs(np.angle(np.exp(1j * (angles[:, None] - angles[None, :]))))).max())


@dataclass(frozen=True)
class _Pixels:
    """Sample pixels of regions: position from the centre, observed shift modulo 8 and owner, shapes (n, 2), (n,)."""

    v: np.ndarray
    shift: np.ndarray
    owner: np.ndarray
    half_diagonal: float


def _sample_pixels(regions: Sequence[Region], labels: np.ndarray, origin: tuple[int, int]) -> _Pixels:
    """Up to ``FIELD_SAMPLES`` evenly spread pixels of each region, with its grid's shift from ``origin``."""
    h, w = labels.shape
    centre = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    v, shift, owner = [], [], []
    for k, region in enumerate(regions):
        x0, y0, x1, y1 = region.bbox
        ys, xs = np.nonzero(labels[y0: y1 + 1, x0: x1 + 1] == region.label)
        pick = np.unique(np.linspace(0, ys.size - 1, min(FIELD_SAMPLES, ys.size)).astype(int)) if ys.size else []
        dx, dy = grid_origin(region.grid)
        v.append(np.column_stack((xs[pick] + x0, ys[pick] + y0)) - centre)
        shift.append(np.tile([(dx - origin[0]) % 8, (dy - origin[1]) % 8], (len(pick), 1)))
        owner.append(np.full(len(pick), k))
    return _Pixels(np.vstack(v).astype(np.float64), np.vstack(shift).astype(np.float64), np.concatenate(owner),
                   float(np.hypot(*centre)))


def _field_offsets(px: _Pixels, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel, the representative of its shift nearest the warp's prediction, less that prediction; and rho."""
    r = np.maximum(np.hypot(px.v[:, 0], px.v[:, 1]), 1e-9)
    rho = r / px.half_diagonal
    predicted = ((a * rho**3 + b * rho) / r)[:, None] * px.v
    return (px.shift - predicted + 4.0) % 8.0 - 4.0, rho


def field_explained(warp: RadialWarp, regions: Sequence[Region], labels: np.ndarray) -> tuple[RadialWarp, list[int]]:
    """The warp's profile refitted on the regions' pixels, and the regions it predicts pixel by pixel.

    The profile is fitted on the regions' centres, with a tolerance for the
    range of directions a region spans, and where the shift is several
    pixels that fit can miss by a few (a region's centre lies up to a pixel
    off the radius, and a representative modulo 8 within the tolerance may
    be the wrong one). Once a warp is established the shift it predicts is
    known at every pixel, ``D(r) u`` with ``u`` the pixel's own direction
    from the centre, so the profile is refitted by least squares on sample
    pixels of every region, each taking the representative of its shift
    nearest the prediction, within a tolerance that shrinks from
    ``PROFILE_MAX_TOL`` to one pixel over ``_REFITS`` rounds. A region is
    explained when, for at least ``MIN_FIELD_SHARE`` of its sample pixels,
    each coordinate of the shift is within one pixel of the prediction
    (rounding to whole pixels moves it by less, whichever way an editor
    rounds). Where the warp moved pixels by tens of pixels (an editor's zoom
    to fill the frame, nearest-neighbour resampling) a region of one grid
    is a patch where the shift rounds to one vector, and it matches
    throughout. A pasted piece keeps one grid over its whole extent, which
    the predicted field matches at a given pixel for about 4 of the 64
    grids.

    Parameters
    ----------
    warp : RadialWarp
        Established by :func:`radial_warp` on ``regions``.
    regions : sequence of Region
        The regions :func:`radial_warp` was given.
    labels : ndarray, shape (H, W), int
        Component map the regions' ``label`` refer to.

    Returns
    -------
    warp : RadialWarp
        With the refitted terms when they explain at least as many regions.
    explained : list of int
        Indices of the regions it explains, by its centres or by its pixels.
    """
    px = _sample_pixels(regions, labels, warp.origin)
    if not px.owner.size:
        return warp, list(warp.explained)

    def explained_by(a: float, b: float) -> np.ndarray:
        off, _ = _field_offsets(px, a, b)
        hits = np.bincount(px.owner, weights=np.all(np.abs(off) < 1.0, axis=1), minlength=len(regions))
        counts = np.bincount(px.owner, minlength=len(regions))
        return (counts > 0) & (hits >= MIN_FIELD_SHARE * counts)

    a, b = warp.terms
    best = explained_by(a, b)
    for tolerance in np.linspace(PROFILE_MAX_TOL, 1.0, _REFITS):
        off, rho = _field_offsets(px, a, b)
        near = np.all(np.abs(off) < tolerance, axis=1)
        if near.sum() < 2:
            break
        r = np.maximum(np.hypot(px.v[near, 0], px.v[near, 1]), 1e-9)
        radial = np.einsum("ij,ij->i", off[near], px.v[near]) / r + (a * rho[near] ** 3 + b * rho[near])
        (a2, b2), *_ = np.linalg.lstsq(np.column_stack((rho[near] ** 3, rho[near])), radial, rcond=None)
        again = explained_by(float(a2), float(b2))
        if again.sum() >= best.sum():
            a, b, best = float(a2), float(b2), again
    refitted = RadialWarp((a, b), a + b, warp.explained, warp.profile, warp.origin)
    return refitted, sorted(set(warp.explained) | set(np.flatnonzero(best).tolist()))


def _one_pixel_steps(bbox: tuple[int, int, int, int], centre: np.ndarray) -> set[tuple[int, int]]:
    """The shifts, modulo 8, that one radial move of about a pixel (0.5 to 1.5, either way) rounds to across a box.

    A shift counts when some move ``D`` rounds to it, ``rint(D u)`` with
    ``u`` each point's own direction from the centre, at
    ``STEP_MIN_SHARE`` or more of the points of the box's middle half: a
    lens correction's band where ``|D|`` nears one rounds to one vector over
    the whole stretch of directions where the other coordinate of ``D u``
    stays below half a pixel (about 60 degrees about an axis, 30 about a
    diagonal), and the region on that grid is that stretch. A shift only
    some points of the box would round to is not a step: across a wide box
    every one-pixel shift is radial somewhere. Empty for a box holding the
    centre.
    """
    x0, y0, x1, y1 = bbox
    corners = np.array([(x0, y0), (x1, y0), (x0, y1), (x1, y1)], dtype=np.float64) - centre
    if np.any(np.hypot(*corners.T) < 1.0) or (x0 <= centre[0] <= x1 and y0 <= centre[1] <= y1):
        return set()
    middle = np.linspace(0.25, 0.75, _STEP_SAMPLES)
    xs, ys = np.meshgrid(x0 + middle * (x1 - x0), y0 + middle * (y1 - y0))
    v = np.column_stack((xs.ravel(), ys.ravel())) - centre
    u = v / np.hypot(*v.T)[:, None]
    d = np.concatenate((-_STEP_LENGTHS, _STEP_LENGTHS))
    moved = np.rint(u[None, :, :] * d[:, None, None]).astype(int) % 8  # (moves, points, 2)
    out = set()
    for per_move in moved:
        shifts, counts = np.unique(per_move, axis=0, return_counts=True)
        out |= {(int(a), int(b)) for (a, b), n in zip(shifts, counts)
                if (a, b) != (0, 0) and n >= STEP_MIN_SHARE * len(per_move)}
    return out


def radial_steps(regions: Sequence[Region], origins: Sequence[tuple[int, int]],
                 shape: tuple[int, int]) -> list[int]:
    """The regions whose grid is the first grid moved by one pixel along their own radius.

    Where too few regions survive to establish a warp (``MIN_REGIONS`` in
    directions ``MIN_SPREAD_DEG`` apart), the band where a lens
    correction's displacement nears one pixel may still leave one: the
    first grid moved by ``D u`` rounded to whole pixels, ``|D|`` between 0.5
    and 1.5. A pasted piece's grid lands on one of those shifts by chance
    for 2 to 4 of the 63 other grids at its place (the step must be the
    rounded radial move over most of the region's box, not at some point of
    it: across a wide box every one-pixel shift is radial somewhere), so such a region is no evidence of a
    paste over a lens correction: the detector names it as possible
    processing, not as a paste. Only without an established warp (with one,
    :func:`field_explained` judges every region).

    Parameters
    ----------
    regions : sequence of Region
        Foreign regions no other processing explains.
    origins : sequence of tuple of int
        Candidate origins ``(dx, dy)`` of the first compression's grid (as
        for :func:`radial_warp`).
    shape : tuple of int
        Image shape ``(H, W)``.

    Returns
    -------
    list of int
        Indices into ``regions``.
    """
    centre = np.array([(shape[1] - 1) / 2.0, (shape[0] - 1) / 2.0])
    out = []
    for i, region in enumerate(regions):
        dx, dy = grid_origin(region.grid)
        steps = _one_pixel_steps(region.bbox, centre)
        if any(((dx - ox) % 8, (dy - oy) % 8) in steps for ox, oy in origins):
            out.append(i)
    return out


def radial_warp(regions: Sequence[Region], origins: Sequence[tuple[int, int]],
                shape: tuple[int, int]) -> RadialWarp | None:
    """The radial warp about the image centre that explains the most regions, if it is established.

    Parameters
    ----------
    regions : sequence of Region
        Foreign regions (grid other than the main one), strongest first.
    origins : sequence of tuple of int
        Candidate origins ``(dx, dy)`` of the first compression's grid where
        the warp is the identity (the main grid's, and the file's own); the
        one whose warp explains the most regions is kept.
    shape : tuple of int
        Image shape ``(H, W)``.

    Returns
    -------
    RadialWarp or None
        None unless at least ``MIN_REGIONS`` regions in directions
        ``MIN_SPREAD_DEG`` apart fit one profile.
    """
    if len(regions) < MIN_REGIONS:
        return None
    best = None
    for origin in dict.fromkeys(origins):
        warp = _warp_from(regions, origin, shape)
        if warp is not None and (best is None or len(warp.explained) > len(best.explained)):
            best = warp
    return best


def _warp_from(regions: Sequence[Region], main_origin: tuple[int, int], shape: tuple[int, int]) -> RadialWarp | None:
    """The best established warp with the first grid's origin at ``main_origin``, or None."""
    centre = np.array([(shape[1] - 1) / 2.0, (shape[0] - 1) / 2.0])
    half_diagonal = float(np.hypot(*centre))
    places = []
    for i, region in enumerate(regions):
        x0, y0, x1, y1 = region.bbox
        v = np.array([(x0 + x1) / 2.0, (y0 + y1) / 2.0]) - centre
        r = float(np.hypot(*v))
        if r >= 1.0:
            places.append(_Place(i, r / half_diagonal, float(np.arctan2(v[1], v[0])),
                                 _radial_lengths(region, main_origin, v / r)))
    seeds = _seeds(places)
    chosen = {p.index for p in seeds}
    places = seeds + [p for p in places if p.index not in chosen]
    profiles = _profiles(seeds)
    if not profiles.size:
        return None
    rho = np.concatenate([np.full(p.lengths.size, p.rho) for p in places])
    lengths = np.concatenate([p.lengths for p in places])
    owner = np.concatenate([np.full(p.lengths.size, k) for k, p in enumerate(places)])
    seeded = owner < len(seeds)
    expected = profiles[:, :1] * rho[seeded][None, :] ** 3 + profiles[:, 1:] * rho[seeded][None, :]
    hit = np.zeros((profiles.shape[0], len(seeds)), dtype=bool)
    np.logical_or.at(hit, (slice(None), owner[seeded]), _fits(lengths[seeded][None, :], expected))
    # The profiles that explain the most seeds are then judged on every region: the most explained wins,
    # and between equals the smallest shift (a larger one can alias onto it modulo 8).
    top = profiles[np.lexsort((np.abs(profiles.sum(axis=1)), -hit.sum(axis=1)))[:_FINALISTS]]
    expected = top[:, :1] * rho[None, :] ** 3 + top[:, 1:] * rho[None, :]
    explains = np.zeros((top.shape[0], len(places)), dtype=bool)
    np.logical_or.at(explains, (slice(None), owner), _fits(lengths[None, :], expected))
    angles = np.array([p.angle for p in places])
    for k in np.lexsort((np.abs(top.sum(axis=1)), -explains.sum(axis=1))):
        if explains[k].sum() < MIN_REGIONS or _spread_deg(angles[explains[k]]) < MIN_SPREAD_DEG:
            continue
        a, b, matched = _refined(places, float(top[k][0]), float(top[k][1]))
        return RadialWarp((float(a), float(b)), float(a + b), tuple(sorted(m[2] for m in matched)),
                          tuple((round(m[0] * half_diagonal, 1), m[1]) for m in matched), main_origin)
    return None
