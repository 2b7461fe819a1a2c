"""Distorted straight lines from sub-pixel edge points (paper sec. 3.3, Fig. 3).

Radial distortion bends the image of a straight 3-D line; junctions, occlusion
and polarity flips (a chessboard row alternates dark/bright above and below the
line) break it into pieces. This module rebuilds the lines:

1. **Link** edge points into chains: each point is joined to the nearest
   neighbouring pixel's point ahead of it and behind it along the edge tangent
   whose gradient direction agrees, and links are kept only when mutual. The
   chains are ordered by pointer jumping (list ranking), so there is no loop
   over points.
2. **Cut** chains where the direction turns (corners, junctions), then split
   pieces that still do not fit the distorted-line model at the point farthest
   from their chord (Douglas-Peucker), round by round, vectorised over pieces.
   Pieces that end up too short, or whose RMS residual about their own smooth
   fit is large, are dropped: the paper's perturbed segments.
3. **Gather** pieces into lines, in rounds of mutual-best merges between
   pieces whose ends are close and that do not overlap. The edge polarity is
   ignored here, so pieces on both sides of a polarity flip are gathered. A
   merge is accepted only when both parts fit *one* distorted line: a straight
   line in undistorted coordinates for some ``|k1| <= max_k1`` with the
   distortion centred on the image centre (paper eqs. 4-8). Curves that no
   admissible distortion can straighten (circles, cables, bezels) are not
   gathered.
4. **Keep** lines at least ``min_length_px`` long whose points lie within
   ``tolerance_px`` of their fitted distorted line (a few outliers are
   dropped), with an RMS residual of at most half of it, and that do not hug
   the image border.

The distorted-line fit is done from additive moment sums, so a merge of two
groups costs O(1) whatever their size; see :func:`_fit_moments`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np
from scipy.spatial import cKDTree

from .edges import EdgePoints
from .geometry import image_centre, norm_scale

__all__ = ["DistortedLine", "extract_lines"]

#: Number of k1 samples of the grid search before parabolic refinement.
_K1_GRID = 21
#: Rounds of Douglas-Peucker splitting of pieces; each round halves them at most.
_SPLIT_ROUNDS = 8
#: Cap on the rounds of pairwise merging (each round about halves the pieces of a line).
_MERGE_ROUNDS = 40
#: Direction noise allowed between the chords of two short pieces, degrees.
_CHORD_NOISE_DEG = 5.0


@dataclass(frozen=True)
class DistortedLine:
    """One distorted straight line gathered from edge pieces.

    Attributes
    ----------
    points : ndarray, shape (N, 2), float64
        Sub-pixel edge points in pixels ``(x, y)``, ordered along the line.
    pieces : int
        How many edge chains were gathered into the line.
    length_px : float
        Length of the polyline through ``points``, pixels (gaps included).
    k1 : float
        Best-fitting ``k1`` of the gathering model (centre of distortion at the
        image centre, normalised coordinates of :mod:`.geometry`). A rough
        value for screening only; :mod:`.k1` estimates it properly.
    rms_px : float
        RMS distance of the points to the fitted distorted line, pixels.
    piece : ndarray, shape (N,), int64
        Which gathered chain each point comes from, numbered 0.. along the
        line. Pieces on either side of a polarity flip can be offset from each
        other by a few tenths of a pixel on real photos (the edge of a blurred,
        tone-mapped step moves towards one side), which a fit may want to absorb.
    edge_index : ndarray, shape (N,), int64
        Index of each point in the :class:`EdgePoints` it was extracted from
        (for its normal, hence polarity, and strength).
    """

    points: np.ndarray
    pieces: int
    length_px: float
    k1: float
    rms_px: float
    piece: np.ndarray
    edge_index: np.ndarray


@dataclass(frozen=True)
class _Fit:
    """Distorted-line fits of G point sets (all arrays shape (G,) unless noted).

    The line is ``normal . p_u = rho`` in undistorted normalised coordinates,
    ``p_u = p (1 + k1 |p|^2)``.
    """

    k1: np.ndarray
    normal: np.ndarray  # (G, 2)
    rho: np.ndarray
    rms_px: np.ndarray


# --------------------------------------------------------------------------- linking


def _inside_border(edges: EdgePoints, shape: tuple[int, int], border_px: float) -> np.ndarray:
    """Mask of points at least ``border_px`` from every image border."""
    x, y = edges.xy[:, 0], edges.xy[:, 1]
    h, w = shape[0], shape[1]
    return (x >= border_px) & (y >= border_px) & (x <= w - 1 - border_px) & (y <= h - 1 - border_px)


@nb.njit(cache=True)
def _link_kernel(xy, normal, pixel, width, cos_max):
    n = xy.shape[0]
    rows = pixel[:, 0]
    cols = pixel[:, 1]
    first_row = rows[0] if n else 0
    n_rows = (rows[-1] - first_row + 2) if n else 1
    # Points of row r lie in row_start[r - first_row] : row_start[r - first_row + 1], by column.
    row_start = np.searchsorted(rows, np.arange(first_row, first_row + n_rows))
    ahead = np.full(n, -1, np.int64)
    behind = np.full(n, -1, np.int64)
    for i in range(n):
        best_ahead = np.inf
        best_behind = np.inf
        nx, ny = normal[i, 0], normal[i, 1]
        # Neighbour positions in row-major order: on equal distances the first wins.
        for k in range(9):
            dr, dc = k // 3 - 1, k % 3 - 1
            c = cols[i] + dc
            r = rows[i] + dr - first_row
            if k == 4 or c < 0 or c >= width or r < 0 or r >= n_rows - 1:
                continue
            lo, hi = row_start[r], row_start[r + 1]
            j = lo + np.searchsorted(cols[lo:hi], c)
            if j >= hi or cols[j] != c:
                continue
            dx = xy[j, 0] - xy[i, 0]
            dy = xy[j, 1] - xy[i, 1]
            along = nx * dy - ny * dx
            across = dx * nx + dy * ny
            if normal[j, 0] * nx + normal[j, 1] * ny < cos_max or abs(along) <= abs(across):
                continue
            dist = np.hypot(dx, dy)
            if along > 0 and dist < best_ahead:
                best_ahead = dist
                ahead[i] = j
            elif along < 0 and dist < best_behind:
                best_behind = dist
                behind[i] = j
    out = np.full(n, -1, np.int64)
    for i in range(n):
        if ahead[i] >= 0 and behind[ahead[i]] == i:
            out[i] = ahead[i]
    return out


def _link(xy: np.ndarray, normal: np.ndarray, pixel: np.ndarray, width: int, max_link_deg: float) -> np.ndarray:
    """Successor of each edge point along its edge, or -1.

    Candidates are the points in the 8 neighbouring pixels whose gradient
    direction is within ``max_link_deg`` (so polarity flips break chains) and
    whose displacement is more along the tangent than across it. The forward
    tangent of point i is its normal turned by +90 degrees; the nearest
    candidate ahead and the nearest behind are chosen, and a link i -> j is
    kept only if j's nearest candidate behind is i. Each point holds one
    pixel, so a compiled loop over its 8 neighbours (found by bisection in
    their row of the sorted pixels) does in one pass what arrays of
    candidate pairs did in several.

    Parameters
    ----------
    xy, normal : ndarray, shape (N, 2)
    pixel : ndarray, shape (N, 2), int
        ``(row, col)``, in strictly increasing row-major order.
    width : int

    Returns
    -------
    ndarray, shape (N,), int64
    """
    return _link_kernel(np.ascontiguousarray(xy, np.float64), np.ascontiguousarray(normal, np.float64),
                        np.ascontiguousarray(pixel, np.int64), int(width), float(np.cos(np.deg2rad(max_link_deg))))


@nb.njit(cache=True)
def _walk(succ, has_pred):
    n = succ.size
    tail = np.full(n, -1, np.int64)
    dist = np.zeros(n, np.int64)
    chain = np.empty(n, np.int64)
    for head in range(n):
        if has_pred[head]:
            continue
        m = 0
        v = head
        while True:
            chain[m] = v
            m += 1
            if succ[v] < 0:
                break
            v = succ[v]
        for q in range(m):
            tail[chain[q]] = chain[m - 1]
            dist[chain[q]] = m - 1 - q
    return tail, dist


def _rank(succ: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tail of each node's chain and its distance to the tail, by walking each chain from its head once.

    Returns
    -------
    tail, dist : ndarray, shape (N,), int64
        Meaningful where not ``cyclic``.
    cyclic : ndarray, shape (N,), bool
        Nodes on a closed chain, which has no head and never reaches a tail.
    """
    has_pred = np.zeros(succ.shape[0], dtype=bool)
    has_pred[succ[succ >= 0]] = True
    tail, dist = _walk(succ, has_pred)
    return tail, dist, tail < 0


def _break_cycles(succ: np.ndarray, cyclic: np.ndarray) -> np.ndarray:
    """Open each closed chain before its lowest-index node (deterministic)."""
    nodes = np.flatnonzero(cyclic)
    lowest = nodes.copy()
    nxt = succ[nodes]
    # Pointer jumping with a running minimum over the cycle, on the cycle nodes only.
    pos = np.full(succ.shape[0], -1, dtype=np.int64)
    pos[nodes] = np.arange(nodes.size)
    nxt_local = pos[nxt]
    for _ in range(max(1, int(np.ceil(np.log2(nodes.size + 1))))):
        lowest = np.minimum(lowest, lowest[nxt_local])
        nxt_local = nxt_local[nxt_local]
    opened = succ.copy()
    opened[nodes[succ[nodes] == lowest[pos[succ[nodes]]]]] = -1
    return opened


def _order_chains(succ: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Order linked points chain by chain, head to tail.

    Returns
    -------
    order : ndarray, shape (N,), int64
        Point indices, chains contiguous, each from head to tail.
    starts : ndarray, shape (N,), bool
        True at the first point of each chain in ``order``.
    """
    tail, dist, cyclic = _rank(succ)
    if cyclic.any():
        tail, dist, _ = _rank(_break_cycles(succ, cyclic))
    order = np.lexsort((-dist, tail))
    t = tail[order]
    starts = np.ones(order.size, dtype=bool)
    starts[1:] = t[1:] != t[:-1]
    return order, starts


# --------------------------------------------------------------------------- segments


def _segment_bounds(starts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segment id of each point and first/last index of each segment."""
    seg = np.cumsum(starts) - 1
    first = np.flatnonzero(starts)
    last = np.append(first[1:], starts.size) - 1
    return seg, first, last


def _cut_turns(xy: np.ndarray, starts: np.ndarray, window: int, max_turn_deg: float) -> np.ndarray:
    """Mask of the points of ordered chains that are not at a turn.

    The turn at point i is the angle between the chords ``p[i-w] -> p[i]`` and
    ``p[i] -> p[i+w]`` of its chain; near a corner it exceeds ``max_turn_deg``
    for about ``w`` points on each side, which are removed, so the corner and
    its poorly localised neighbourhood go.
    """
    seg, first, last = _segment_bounds(starts)
    i = np.arange(xy.shape[0])
    has_both = (i - window >= first[seg]) & (i + window <= last[seg])
    ib = np.clip(i - window, 0, None)
    ia = np.clip(i + window, None, xy.shape[0] - 1)
    u = xy - xy[ib]
    v = xy[ia] - xy
    cos_turn = np.einsum("ij,ij->i", u, v) / np.maximum(np.hypot(*u.T) * np.hypot(*v.T), 1e-12)
    return ~has_both | (cos_turn >= np.cos(np.deg2rad(max_turn_deg)))


def _restart(starts: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Segment starts after removing points: a removed point also ends a segment."""
    seg = np.cumsum(starts)
    gap = np.ones(starts.size, dtype=bool)
    gap[1:] = ~keep[:-1]
    new = (starts | gap)[keep]
    kept_seg = seg[keep]
    new[1:] |= kept_seg[1:] != kept_seg[:-1]
    return new


def _drop_short(starts: np.ndarray, min_points: int) -> np.ndarray:
    """Mask of the points of segments with at least ``min_points`` points."""
    seg, first, last = _segment_bounds(starts)
    return (last - first + 1 >= min_points)[seg]


# --------------------------------------------------------------------------- fitting

# Column layout of the moment sums of a point set, p = (x, y) normalised,
# q = p |p|^2, so that the undistorted point is z = p + k1 q (paper eqs. 6-7).
_N, _PX, _PY, _QX, _QY = 0, 1, 2, 3, 4
#: Point sets fitted at once by :func:`_fit_moments`.
_FIT_CHUNK = 16384
_PXX, _PXY, _PYY = 5, 6, 7
_PXQX, _PXQY, _PYQX, _PYQY = 8, 9, 10, 11
_QXX, _QXY, _QYY = 12, 13, 14
_R2, _R4 = 15, 16
_N_MOMENTS = 17


def _point_moments(p: np.ndarray) -> np.ndarray:
    """Per-point moment terms, shape (N, 17), of normalised points ``p`` (N, 2)."""
    x, y = p[:, 0], p[:, 1]
    r2 = x * x + y * y
    qx, qy = x * r2, y * r2
    return np.column_stack(
        (np.ones_like(x), x, y, qx, qy, x * x, x * y, y * y,
         x * qx, x * qy, y * qx, y * qy, qx * qx, qx * qy, qy * qy, r2, r2 * r2)
    )


def _z_moments(m: np.ndarray, k: np.ndarray):
    """Sums of z = p + k q and of z z^T for moment rows ``m`` (..., 17), k broadcast."""
    sx = m[..., _PX] + k * m[..., _QX]
    sy = m[..., _PY] + k * m[..., _QY]
    sxx = m[..., _PXX] + 2 * k * m[..., _PXQX] + k * k * m[..., _QXX]
    sxy = m[..., _PXY] + k * (m[..., _PXQY] + m[..., _PYQX]) + k * k * m[..., _QXY]
    syy = m[..., _PYY] + 2 * k * m[..., _PYQY] + k * k * m[..., _QYY]
    return sx, sy, sxx, sxy, syy


def _magnification2(m: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Mean of (1 + k r^2)^2: converts undistorted residuals back to distorted ones."""
    n = m[..., _N]
    return 1 + 2 * k * m[..., _R2] / n + k * k * m[..., _R4] / n


def _objective(m: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Mean squared residual (normalised units) of the best line through z(k)."""
    n = m[..., _N]
    sx, sy, sxx, sxy, syy = _z_moments(m, k)
    mx, my = sx / n, sy / n
    a, b, c = sxx / n - mx * mx, sxy / n - mx * my, syy / n - my * my
    lam = 0.5 * (a + c) - np.sqrt(0.25 * (a - c) ** 2 + b * b)
    return np.maximum(lam, 0.0) / _magnification2(m, k)


def _fit_moments(m: np.ndarray, max_k1: float, scale_px: float) -> _Fit:
    """Fit one distorted line to each of G point sets given their moment sums.

    For each set, ``k1`` in ``[-max_k1, max_k1]`` is chosen to minimise the
    residual of the total-least-squares line through the undistorted points
    (paper eqs. 6-8 and the cost below them, with the line refitted for every
    k1, which removes the bias of fixing it from the distorted points; see the
    project notes). The residual of a 2-D point set about its best line is the
    smaller eigenvalue of its covariance, a closed form of the moment sums, so
    the search is a grid over k1 refined by a parabola through the three best
    samples, vectorised over sets.

    Parameters
    ----------
    m : ndarray, shape (G, 17)
        Moment sums from :func:`_point_moments`.
    max_k1 : float
    scale_px : float
        Pixels per normalised unit.
    """
    if m.shape[0] > _FIT_CHUNK:
        # The grid search holds G x _K1_GRID values per moment term: in bounded chunks, not all at once (a
        # drawn checkerboard offers millions of candidate pairs).
        parts = [_fit_moments(m[i: i + _FIT_CHUNK], max_k1, scale_px) for i in range(0, m.shape[0], _FIT_CHUNK)]
        return _Fit(*(np.concatenate([getattr(f, name) for f in parts]) for name in ("k1", "normal", "rho", "rms_px")))
    grid = np.linspace(-max_k1, max_k1, _K1_GRID)
    obj = _objective(m[:, None, :], grid[None, :])
    best = np.clip(np.argmin(obj, axis=1), 1, _K1_GRID - 2)
    rows = np.arange(m.shape[0])
    f0, f1, f2 = obj[rows, best - 1], obj[rows, best], obj[rows, best + 1]
    curv = f0 - 2 * f1 + f2
    step = grid[1] - grid[0]
    shift = np.where(curv > 0, 0.5 * (f0 - f2) / np.where(curv > 0, curv, 1.0), 0.0)
    k = np.clip(grid[best] + np.clip(shift, -1, 1) * step, -max_k1, max_k1)
    n = m[:, _N]
    sx, sy, sxx, sxy, syy = _z_moments(m, k)
    mx, my = sx / n, sy / n
    a, b, c = sxx / n - mx * mx, sxy / n - mx * my, syy / n - my * my
    theta = 0.5 * np.arctan2(2 * b, a - c)
    normal = np.column_stack((-np.sin(theta), np.cos(theta)))
    rho = normal[:, 0] * mx + normal[:, 1] * my
    rms = np.sqrt(_objective(m, k)) * scale_px
    return _Fit(k1=k, normal=normal, rho=rho, rms_px=rms)


def _rms_under(m: np.ndarray, fit: _Fit, scale_px: float) -> np.ndarray:
    """RMS residual, pixels, of point sets with moments ``m`` (G, 17) about given fits."""
    n = m[:, _N]
    sx, sy, sxx, sxy, syy = _z_moments(m, fit.k1)
    nx, ny, rho = fit.normal[:, 0], fit.normal[:, 1], fit.rho
    sse = nx * nx * sxx + 2 * nx * ny * sxy + ny * ny * syy - 2 * rho * (nx * sx + ny * sy) + n * rho * rho
    return np.sqrt(np.maximum(sse, 0.0) / n / _magnification2(m, fit.k1)) * scale_px


def _residuals_px(p: np.ndarray, owner: np.ndarray, fit: _Fit, scale_px: float) -> np.ndarray:
    """Signed residual, pixels, of each normalised point ``p`` (N, 2) about the fit of its set."""
    r2 = np.einsum("ij,ij->i", p, p)
    k = fit.k1[owner]
    z = p * (1 + k * r2)[:, None]
    e = np.einsum("ij,ij->i", z, fit.normal[owner]) - fit.rho[owner]
    return e / (1 + k * r2) * scale_px


def _segment_sums(values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Sums of contiguous segments (rows of ``values``) starting where ``starts``."""
    return np.add.reduceat(values, np.flatnonzero(starts), axis=0)


def _fit_segments(p: np.ndarray, starts: np.ndarray, max_k1: float, scale_px: float):
    """Distorted-line fit of each segment and each point's absolute residual, pixels."""
    seg, first, _ = _segment_bounds(starts)
    fit = _fit_moments(_segment_sums(_point_moments(p), starts), max_k1, scale_px)
    res = np.abs(_residuals_px(p, seg, fit, scale_px))
    return fit, res, np.maximum.reduceat(res, first)


def _farthest_from_chord(xy: np.ndarray, starts: np.ndarray, which: np.ndarray) -> np.ndarray:
    """Index of the point of each segment in ``which`` (mask over segments) farthest from its chord.

    On a closed curve the chord degenerates; the distance to the first point is used instead.
    """
    seg, first, last = _segment_bounds(starts)
    a, b = xy[first][seg], xy[last][seg]
    chord = b - a
    clen = np.hypot(chord[:, 0], chord[:, 1])
    rel = xy - a
    cross = np.abs(chord[:, 0] * rel[:, 1] - chord[:, 1] * rel[:, 0])
    dev = np.where(clen > 1.0, cross / np.maximum(clen, 1e-12), np.hypot(rel[:, 0], rel[:, 1]))
    dev[~which[seg]] = -1.0
    top = np.maximum.reduceat(dev, first)
    at_top = np.flatnonzero((dev == top[seg]) & which[seg])
    _, one = np.unique(seg[at_top], return_index=True)
    cut = at_top[one]
    return cut[cut != first[seg[cut]]]


def _split_pieces(xy, p, starts, tolerance_px, max_rms_px, max_k1, scale_px, min_points):
    """Split chains into pieces that each fit one distorted line.

    Each round fits every segment; a segment with a point farther than
    ``tolerance_px`` from its fit is split at the point farthest from its chord
    (Douglas-Peucker). Afterwards, segments still failing, shorter than
    ``min_points``, or jagged (RMS residual above ``max_rms_px`` about their own
    smooth fit: the paper's perturbed segments) are removed.

    Returns
    -------
    keep : ndarray, shape (N,), bool
    starts : ndarray, shape (N,), bool
        Segment starts (meaningful where ``keep``).
    """
    starts = starts.copy()
    keep = _drop_short(starts, min_points)
    # A segment that fits is never split, so each round refits only the pieces of the last round's splits.
    pending = keep.copy()
    for _ in range(_SPLIT_ROUNDS):
        idx = np.flatnonzero(pending)
        if idx.size == 0:
            break
        _, _, worst = _fit_segments(p[idx], starts[idx], max_k1, scale_px)
        bad = worst > tolerance_px
        pending[idx] = bad[np.cumsum(starts[idx]) - 1]
        if not bad.any():
            break
        starts[idx[_farthest_from_chord(xy[idx], starts[idx], bad)]] = True
        long_enough = _drop_short(starts[idx], min_points)
        keep[idx] &= long_enough
        pending[idx] &= long_enough
    idx = np.flatnonzero(keep)
    fit, _, worst = _fit_segments(p[idx], starts[idx], max_k1, scale_px)
    seg = np.cumsum(starts[idx]) - 1
    keep[idx] = ((worst <= tolerance_px) & (fit.rms_px <= max_rms_px))[seg]
    return keep, starts


# --------------------------------------------------------------------------- gathering


@dataclass(frozen=True)
class _GatherRule:
    """When two groups of pieces may be gathered into one line."""

    max_k1: float
    scale_px: float  # pixels per normalised unit
    max_gap_px: float
    part_rms_px: float  # largest RMS of either part about the merged fit
    max_overlap_px: float
    max_bend: float  # largest curvature of a distorted line, 1/pixel


@dataclass
class _Groups:
    """Groups of pieces being gathered (arrays indexed by group unless noted).

    The ends of a group are two of its pieces' ends, so the end points are
    stored once, ``end_xy[2 * piece + (0 | 1)]`` = first | last point of the
    piece, and groups refer to them by index.
    """

    moments: np.ndarray  # (G, 17)
    end_ids: np.ndarray  # (G, 2) indices into end_xy
    pieces: np.ndarray  # (G,) int
    label: np.ndarray  # (P,) group of each piece
    end_xy: np.ndarray  # (2P, 2) pixels


def _first_by_key(key: np.ndarray, cost: np.ndarray, value: np.ndarray, size: int) -> np.ndarray:
    """For each key in ``range(size)``, the value of lowest cost (first on ties), or -1."""
    order = np.lexsort((cost, key))
    key, value = key[order], value[order]
    first = np.ones(key.size, dtype=bool)
    first[1:] = key[1:] != key[:-1]
    out = np.full(size, -1, dtype=np.int64)
    out[key[first]] = value[first]
    return out


def _open_pairs(g: _Groups, pairs: np.ndarray) -> np.ndarray:
    """The end pairs whose two ends are still ends of two different groups."""
    is_open = np.zeros(g.end_xy.shape[0], dtype=bool)
    is_open[g.end_ids.ravel()] = True
    ok = is_open[pairs[:, 0]] & is_open[pairs[:, 1]]
    ok &= g.label[pairs[:, 0] // 2] != g.label[pairs[:, 1] // 2]
    return pairs[ok]


def _group_pairs(g: _Groups, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distinct group pairs ``a < b`` of the end pairs, with their smallest end gap."""
    ga, gb = g.label[pairs[:, 0] // 2], g.label[pairs[:, 1] // 2]
    n = np.int64(g.pieces.size)
    # One integer key per group pair: a single sort, then the smallest gap of each run of equal keys.
    key = np.minimum(ga, gb).astype(np.int64) * n + np.maximum(ga, gb)
    gap = np.hypot(*(g.end_xy[pairs[:, 0]] - g.end_xy[pairs[:, 1]]).T)
    order = np.argsort(key)
    key = key[order]
    first = np.flatnonzero(np.concatenate(([True], key[1:] != key[:-1])))
    key = key[first]
    return key // n, key % n, np.minimum.reduceat(gap[order], first)


def _roughly_aligned(g: _Groups, a, b, gap, rule: _GatherRule) -> np.ndarray:
    """Cheap pre-test before fitting: the two groups' chords point alike.

    A distorted line turns by at most ``max_bend`` per pixel, so the chords of
    two pieces of it differ by at most ``max_bend`` times half their summed
    lengths and gap, plus a few degrees for the direction noise of short chords.
    """
    ca = g.end_xy[g.end_ids[a, 1]] - g.end_xy[g.end_ids[a, 0]]
    cb = g.end_xy[g.end_ids[b, 1]] - g.end_xy[g.end_ids[b, 0]]
    la, lb = np.hypot(*ca.T), np.hypot(*cb.T)
    cos_ab = np.abs(np.einsum("ij,ij->i", ca, cb)) / np.maximum(la * lb, 1e-12)
    allowed = np.deg2rad(_CHORD_NOISE_DEG) + rule.max_bend * 0.5 * (la + lb + gap)
    return cos_ab >= np.cos(np.minimum(allowed, 0.5 * np.pi))


def _overlap_px(g: _Groups, a, b, tangent: np.ndarray) -> np.ndarray:
    """Overlap, pixels, of two groups' extents projected on the merged tangent."""
    sa = np.einsum("gej,gj->ge", g.end_xy[g.end_ids[a]], tangent)
    sb = np.einsum("gej,gj->ge", g.end_xy[g.end_ids[b]], tangent)
    return np.minimum(sa.max(1), sb.max(1)) - np.maximum(sa.min(1), sb.min(1))


def _merge_round(g: _Groups, pairs: np.ndarray, rule: _GatherRule) -> _Groups | None:
    """One round of mutual-best merges; None when nothing merges.

    Each candidate pair is fitted as one distorted line (from the summed
    moments) and accepted when each part fits it with an RMS of at most
    ``part_rms_px`` and the two do not overlap along it; its cost is the
    larger part RMS, then the gap. Each group picks its cheapest partner and
    mutual choices merge, so a line grows from all its pieces at once and no
    group is torn between two partners.
    """
    a, b, gap = _group_pairs(g, pairs)
    ok = _roughly_aligned(g, a, b, gap, rule)
    a, b, gap = a[ok], b[ok], gap[ok]
    if a.size == 0:
        return None
    fit = _fit_moments(g.moments[a] + g.moments[b], rule.max_k1, rule.scale_px)
    cost = np.maximum(_rms_under(g.moments[a], fit, rule.scale_px), _rms_under(g.moments[b], fit, rule.scale_px))
    tangent = np.column_stack((-fit.normal[:, 1], fit.normal[:, 0]))
    ok = (cost <= rule.part_rms_px) & (_overlap_px(g, a, b, tangent) <= rule.max_overlap_px)
    a, b, gap, cost = a[ok], b[ok], gap[ok], cost[ok]
    if a.size == 0:
        return None
    src, dst = np.concatenate((a, b)), np.concatenate((b, a))
    order = np.lexsort((np.concatenate((gap, gap)), np.concatenate((cost, cost))))
    best = _first_by_key(src[order], np.arange(order.size), dst[order], g.pieces.size)
    mutual = (best >= 0) & (best[np.maximum(best, 0)] == np.arange(best.size))
    lo = np.flatnonzero(mutual & (np.arange(best.size) < best))
    if lo.size == 0:
        return None
    return _apply_merges(g, lo, best[lo])


def _apply_merges(g: _Groups, lo: np.ndarray, hi: np.ndarray) -> _Groups:
    """Merge group ``hi[i]`` into ``lo[i]`` and renumber groups densely.

    The merged group's ends are the two farthest apart of the four old ends.
    """
    target = np.arange(g.pieces.size)
    target[hi] = lo
    survivors = np.flatnonzero(target == np.arange(target.size))
    new_id = np.full(target.size, -1, dtype=np.int64)
    new_id[survivors] = np.arange(survivors.size)
    to = new_id[target]
    moments = np.zeros((survivors.size, _N_MOMENTS))
    np.add.at(moments, to, g.moments)
    pieces = np.bincount(to, weights=g.pieces, minlength=survivors.size).astype(np.int64)
    end_ids = g.end_ids[survivors].copy()
    four = np.concatenate((g.end_ids[lo], g.end_ids[hi]), axis=1)
    pi, pj = np.triu_indices(4, 1)
    xy4 = g.end_xy[four]
    span = np.hypot(*(xy4[:, pi] - xy4[:, pj]).transpose(2, 0, 1))
    far = np.argmax(span, axis=1)
    rows = np.arange(lo.size)
    end_ids[new_id[lo]] = np.column_stack((four[rows, pi[far]], four[rows, pj[far]]))
    return _Groups(moments=moments, end_ids=end_ids, pieces=pieces, label=to[g.label], end_xy=g.end_xy)


def _gather(xy: np.ndarray, p: np.ndarray, starts: np.ndarray, rule: _GatherRule) -> _Groups:
    """Gather pieces (segments of ordered points) into groups, round by round.

    Candidate partners are found once, as pairs of piece ends closer than
    ``max_gap_px``: a merged group's ends are old ends, so later rounds only
    discard the pairs whose ends became interior.
    """
    _, first, last = _segment_bounds(starts)
    end_xy = np.stack((xy[first], xy[last]), axis=1).reshape(-1, 2)
    g = _Groups(
        moments=_segment_sums(_point_moments(p), starts),
        end_ids=np.arange(end_xy.shape[0]).reshape(-1, 2),
        pieces=np.ones(first.size, dtype=np.int64),
        label=np.arange(first.size),
        end_xy=end_xy,
    )
    pairs = cKDTree(end_xy).query_pairs(rule.max_gap_px, output_type="ndarray")
    for _ in range(_MERGE_ROUNDS):
        pairs = _open_pairs(g, pairs)
        merged = _merge_round(g, pairs, rule) if pairs.size else None
        if merged is None:
            break
        g = merged
    return g


# --------------------------------------------------------------------------- output


def _hugs_border(points: np.ndarray, shape: tuple[int, int], band_px: float) -> bool:
    """True if all points lie within ``band_px`` of one and the same image side."""
    x, y = points[:, 0], points[:, 1]
    h, w = shape[0], shape[1]
    return bool(x.max() < band_px or y.max() < band_px or x.min() > w - 1 - band_px or y.min() > h - 1 - band_px)


def _build_lines(xy, p, eid, owner, piece, g: _Groups, keep, rule: _GatherRule, *, tolerance_px, max_outliers):
    """Final checks and :class:`DistortedLine` objects for the groups where ``keep``.

    ``xy``, ``p``, ``eid``, ``owner`` and ``piece`` are the gathered points'
    pixel and normalised positions, edge ids, owning group and piece, one
    row each; ``g`` the groups, ``keep`` which of them to build.

    Points farther than ``tolerance_px`` from their group's fit are dropped;
    a group keeps its line if they are at most ``max_outliers`` of its points
    and the RMS of the rest is at most ``rule.part_rms_px``. Points are ordered
    by their position along the fitted line's direction, which is monotonic on
    a distorted line for any admissible ``k1``.
    """
    fit = _fit_moments(g.moments, rule.max_k1, rule.scale_px)
    sel = keep[owner]
    xy, p, eid, owner, piece = xy[sel], p[sel], eid[sel], owner[sel], piece[sel]
    res = _residuals_px(p, owner, fit, rule.scale_px)
    inlier = np.abs(res) <= tolerance_px
    n_groups = g.pieces.size
    n_all = np.bincount(owner, minlength=n_groups)
    n_in = np.bincount(owner, weights=inlier, minlength=n_groups)
    ss_in = np.bincount(owner, weights=np.where(inlier, res * res, 0.0), minlength=n_groups)
    rms_in = np.sqrt(ss_in / np.maximum(n_in, 1))
    good = keep & (n_in >= (1 - max_outliers) * n_all) & (rms_in <= rule.part_rms_px)
    sel = good[owner] & inlier
    xy, eid, owner, piece = xy[sel], eid[sel], owner[sel], piece[sel]
    tangent = np.column_stack((-fit.normal[:, 1], fit.normal[:, 0]))
    order = np.lexsort((np.einsum("ij,ij->i", xy, tangent[owner]), owner))
    xy, eid, owner, piece = xy[order], eid[order], owner[order], piece[order]
    ids, first = np.unique(owner, return_index=True)
    bounds = np.append(first, owner.size)
    lines = []
    for gi, s, e in zip(ids, bounds[:-1], bounds[1:]):
        step = np.diff(xy[s:e], axis=0)
        pieces_here, first_seen = np.unique(piece[s:e], return_index=True)
        rank = np.empty(pieces_here.size, dtype=np.int64)
        rank[np.argsort(first_seen)] = np.arange(pieces_here.size)
        lines.append(
            DistortedLine(
                points=xy[s:e],
                pieces=int(pieces_here.size),
                length_px=float(np.hypot(step[:, 0], step[:, 1]).sum()),
                k1=float(fit.k1[gi]),
                rms_px=float(rms_in[gi]),
                piece=rank[np.searchsorted(pieces_here, piece[s:e])],
                edge_index=eid[s:e],
            )
        )
    return lines


def _pieces(edges: EdgePoints, shape, border_px, max_link_deg, turn_window, max_turn_deg, min_points):
    """Chains cut at turns.

    Returns
    -------
    eid : ndarray, shape (N,), int64
        Edge-point indices, chain by chain in order along each chain.
    starts : ndarray, shape (N,), bool
        True at the first point of each chain.
    """
    w = shape[1]
    eid = np.flatnonzero(_inside_border(edges, shape, border_px))
    eid = eid[np.argsort(edges.pixel[eid, 0] * w + edges.pixel[eid, 1], kind="stable")]
    order, starts = _order_chains(_link(edges.xy[eid], edges.normal[eid], edges.pixel[eid], w, max_link_deg))
    eid = eid[order]
    keep = _cut_turns(edges.xy[eid], starts, turn_window, max_turn_deg)
    starts = _restart(starts, keep)
    eid = eid[keep]
    keep = _drop_short(starts, min_points)
    return eid[keep], starts[keep]


def extract_lines(
    edges: EdgePoints,
    shape: tuple[int, int],
    min_length_px: float,
    *,
    max_k1: float = 0.35,
    tolerance_px: float = 1.5,
    max_rms_px: float = 0.4,
    max_gap_px: float | None = None,
    border_px: float = 6.0,
    hug_px: float = 15.0,
    max_link_deg: float = 45.0,
    turn_window: int = 4,
    max_turn_deg: float = 20.0,
    min_piece_px: float = 10.0,
    max_overlap_px: float = 3.0,
    max_outliers: float = 0.05,
) -> list[DistortedLine]:
    """Distorted straight lines made of sub-pixel edge points (paper sec. 3.3).

    Parameters
    ----------
    edges : EdgePoints
        From :func:`.edges.subpixel_edges`.
    shape : tuple of int
        Image shape ``(H, W)``.
    min_length_px : float
        Shortest line returned, pixels (polyline length, gaps included).
    max_k1 : float
        Largest ``|k1|`` (normalised units, image-centred model of
        :mod:`.geometry`) whose bending a gathered line may show.
    tolerance_px : float
        Every returned point lies within this distance, pixels, of its line's
        fitted distorted line (the paper's tolerance region, Fig. 3). Pieces are
        split until they fit within it; a merge is accepted when each part fits
        the merged line with an RMS of at most half of it, and a returned line
        has an RMS of at most half of it.
    max_rms_px : float
        Largest RMS residual of a piece about its own smooth fit, pixels:
        perturbed (jagged) pieces are rejected even within the tolerance region.
    max_gap_px : float or None
        Largest gap between the ends of two gathered pieces, pixels; default
        1 % of the larger image side, at least 12 px.
    border_px : float
        Edge points closer than this to the image border are ignored.
    hug_px : float
        Lines lying entirely within this distance of one image side are
        dropped: frames and padding bands of a few pixels are artefacts.
    max_link_deg : float
        Largest gradient-direction change between linked neighbouring points.
    turn_window : int
        Chord length, in points, of the turn measure.
    max_turn_deg : float
        Chains are cut where they turn by more than this over ``turn_window``.
    min_piece_px : float
        Shortest piece kept for gathering, in points (about pixels).
    max_overlap_px : float
        Largest overlap along the line of two gathered pieces, pixels; keeps
        parallel neighbouring edges apart.
    max_outliers : float
        Largest fraction of a line's points outside ``tolerance_px``; those
        points are removed from the returned line.

    Returns
    -------
    list of DistortedLine
        Longest first; ties by first point ``(x, y)``.

    Notes
    -----
    Pieces are gathered into one line when together they fit one distorted
    straight line, i.e. the image of a straight line under eq. (1) of [1]_
    with some ``|k1| <= max_k1``, within ``tolerance_px`` (the tolerance
    region of [1]_, fig. 3).

    References
    ----------
    .. [1] H. R. Chennamma, L. Rangarajan, Image splicing detection using
       inherent lens radial distortion, IJCSI 7(6), 2010, sec. 3.3.

    Examples
    --------
    The four sides of a bright rectangle, longest first:

    >>> from forensics_plugins.lens_distortion.edges import subpixel_edges
    >>> img = np.zeros((200, 300))
    >>> img[50:150, 60:240] = 1.0
    >>> lines = extract_lines(subpixel_edges(img), img.shape, min_length_px=80)
    >>> [round(line.length_px) for line in lines]
    [177, 177, 97, 97]
    """
    h, w = shape[0], shape[1]
    scale_px = norm_scale(shape)
    half_diagonal = np.hypot(w - 1, h - 1) / 2 / scale_px
    rule = _GatherRule(
        max_k1=max_k1,
        scale_px=scale_px,
        max_gap_px=max(12.0, 0.01 * max(h, w)) if max_gap_px is None else max_gap_px,
        part_rms_px=0.5 * tolerance_px,
        max_overlap_px=max_overlap_px,
        # Curvature of a distorted straight line is about 2 |k1| d (normalised
        # units, d its distance from the centre); 1.5 times that covers the
        # higher-order terms of a strong distortion.
        max_bend=3.0 * max_k1 * half_diagonal / scale_px,
    )
    min_points = max(3, int(np.ceil(min_piece_px)))
    eid, starts = _pieces(edges, shape, border_px, max_link_deg, turn_window, max_turn_deg, min_points)
    if eid.size == 0:
        return []
    xy = edges.xy[eid]
    p = (xy - image_centre(shape)) / scale_px
    keep, starts = _split_pieces(xy, p, starts, tolerance_px, max_rms_px, max_k1, scale_px, min_points)
    starts = _restart(starts, keep)
    xy, p, eid = xy[keep], p[keep], eid[keep]
    if eid.size == 0:
        return []

    g = _gather(xy, p, starts, rule)
    piece = np.cumsum(starts) - 1
    owner = g.label[piece]
    extent = np.hypot(*(g.end_xy[g.end_ids[:, 0]] - g.end_xy[g.end_ids[:, 1]]).T)
    lines = _build_lines(xy, p, eid, owner, piece, g, extent >= 0.9 * min_length_px, rule, tolerance_px=tolerance_px,
                         max_outliers=max_outliers)
    lines = [ln for ln in lines if ln.length_px >= min_length_px and not _hugs_border(ln.points, shape, hug_px)]
    lines.sort(key=lambda ln: (-ln.length_px, ln.points[0, 0], ln.points[0, 1]))
    return lines
