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
R)^3`` (the one-term radial model, paper eqs. 1-5; ``R`` the half
diagonal), and a grid only shows it modulo 8: a shift of (8, 1) px reads as
(0, 1). So a region is explained by the warp when one representative of
its grid's shift modulo 8 (``s + 8 (i, j)``) lies along the radius through
its centre, within ``PERP_TOL`` pixels (rounding each coordinate moves it
by at most 0.5, and the region spans a range of directions), with a length
within ``PROFILE_TOL`` (or a share ``PROFILE_REL`` of ``D``, for the higher
terms of real corrections, at most ``PROFILE_MAX_TOL``) of ``D`` at its
distance. ``a`` (its sign: the
warp pushed pixels outwards or inwards) is the value that explains the most
regions. A paste matches a given profile at its place by chance in a few
per cent of placements where ``D`` is a few pixels (about 4 of the 64
shifts modulo 8), up to about a fifth far out where it is tens of pixels
(the tolerance then covers 12 of the 64), so the warp is
named only when at least ``MIN_REGIONS`` regions in directions at least
``MIN_SPREAD_DEG`` apart fit one profile, and regions it does not explain
stay foreign: a piece pasted into a lens-corrected photo is still
reported.

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

import numpy as np

from .regions import Region
from .votes import grid_origin

PERP_TOL = 1.0
PROFILE_TOL = 1.0
PROFILE_REL = 0.15
#: Beyond a few pixels the shift's representatives modulo 8 crowd every length: the tolerance stops here.
PROFILE_MAX_TOL = 3.0
MIN_REGIONS = 2
MIN_SPREAD_DEG = 60.0
#: Shifts searched, pixels at the half diagonal: from half a pixel to far beyond any editor's correction.
_PROFILE = np.geomspace(0.5, 400.0, 600)
#: Representatives of a shift modulo 8 within this many periods of it.
_WRAPS = np.array([(i, j) for i in range(-6, 7) for j in range(-6, 7)], dtype=np.float64)


@dataclass(frozen=True)
class RadialWarp:
    """A radial resampling of the whole photo after its first compression.

    Attributes
    ----------
    sign : int
        +1 when the grid moved outwards (the warp pushed pixels away from
        the centre), -1 inwards.
    at_corner_px : float
        ``|D|`` at the half diagonal of the fitted profile ``D(r) = a (r / R)^3``.
    explained : tuple of int
        Indices (into the regions given) of the regions it explains.
    profile : tuple of (float, float)
        For each explained region, in order of distance: its distance from
        the centre and its grid's shift along the radius, pixels (the
        correction's displacement sampled where the old grid shows it).
    """

    sign: int
    at_corner_px: float
    explained: tuple[int, ...]
    profile: tuple[tuple[float, float], ...]


def _radial_lengths(region: Region, main_origin: tuple[int, int], u: np.ndarray) -> np.ndarray:
    """Signed lengths along ``u`` of the region's shift representatives that lie along its radius, shape (k,)."""
    dx, dy = grid_origin(region.grid)
    shift = np.array([(dx - main_origin[0]) % 8, (dy - main_origin[1]) % 8], dtype=np.float64)
    candidates = shift[None, :] + 8.0 * _WRAPS
    perp = np.abs(candidates @ np.array([-u[1], u[0]]))
    return (candidates @ u)[perp <= PERP_TOL]


def radial_warp(regions: Sequence[Region], main_origin: tuple[int, int], shape: tuple[int, int]) -> RadialWarp | None:
    """The radial warp about the image centre that explains the most regions, if it is established.

    Parameters
    ----------
    regions : sequence of Region
        Foreign regions (grid other than the main one).
    main_origin : tuple of int
        The main grid's origin ``(dx, dy)``.
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
    centre = np.array([(shape[1] - 1) / 2.0, (shape[0] - 1) / 2.0])
    half_diagonal = float(np.hypot(*centre))
    places = []
    for i, region in enumerate(regions):
        x0, y0, x1, y1 = region.bbox
        v = np.array([(x0 + x1) / 2.0, (y0 + y1) / 2.0]) - centre
        r = float(np.hypot(*v))
        if r >= 1.0:
            places.append((i, r, float(np.arctan2(v[1], v[0])), _radial_lengths(region, main_origin, v / r)))
    best: RadialWarp | None = None
    for sign in (1, -1):
        for corner in _PROFILE:
            matched = []
            for i, r, angle, lengths in places:
                expected = sign * corner * (r / half_diagonal) ** 3
                miss = np.abs(lengths - expected)
                tolerance = min(max(PROFILE_TOL, PROFILE_REL * abs(expected)), PROFILE_MAX_TOL)
                if lengths.size and miss.min() <= tolerance and abs(expected) >= 0.5:
                    matched.append((r, float(sign * lengths[np.argmin(miss)]), i, angle))
            # The most regions; between equals, the smallest shift (a larger one can alias onto it modulo 8).
            if len(matched) < MIN_REGIONS or (best is not None and (len(matched), -corner) <=
                                              (len(best.explained), -best.at_corner_px)):
                continue
            angles = np.array([m[3] for m in matched])
            spread = np.degrees(np.abs(np.angle(np.exp(1j * (angles[:, None] - angles[None, :]))))).max()
            if spread >= MIN_SPREAD_DEG:
                matched.sort()
                best = RadialWarp(sign, float(corner), tuple(sorted(m[2] for m in matched)),
                                  tuple((round(m[0], 1), m[1]) for m in matched))
    return best
