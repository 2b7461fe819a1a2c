"""The mosaic of a lens-corrected photo: the phase a radial resampling gave each block, and departures from it.

A lens correction moves the content at distance ``r`` from the centre by
``D(r)`` along its radius (:class:`forensics_core.RadialResampling`, which
``jpeg_grid`` establishes from the first compression's grid). Where a block
moved by whole pixels ``(sy, sx)``, as a nearest-neighbour correction moves
every pixel, and as any interpolation moves those where ``D`` is near a
whole number, the block keeps the camera's demosaicing trace, shifted by
``(sy mod 2, sx mod 2)``: green lies on the other diagonal where ``sy + sx``
is odd, and red and blue swap places where both are odd. So a corrected
photo shows rings and patches of other phases that follow ``D`` rounded at
each pixel, and a scan against the photo's one phase reports them as
regions of another mosaic.

When the warp is known, each block's expected phase is the one it gives:
the detector first checks that the mosaic follows the warp across the whole
photo (among the blocks that vote on the diagonal and whose pixels the warp
moves by an odd or by an even sum on at least :data:`DECISIVE_SHARE` of
them, the votes agree with that prediction more often than the two maps'
own shares of the other diagonal would make them by chance: binomial tail
at most :data:`MAX_LOG10_P`, doubled for the choice of which diagonal is
the photo's own; the profile first refitted to the mosaic, :func:`fitted`),
and then asks the region scan's questions against the predicted phase
instead of the photo's one phase. Where jpeg_grid establishes no warp,
the detector proposes one from the mosaic itself (:func:`searched`), and
uses it only when it also accounts for the blocks on the other diagonal
(:func:`accounts_for`). A pasted piece keeps its
own mosaic over its whole extent, which departs from the warp's rings
unless it happens to lie where they put that phase.

References
----------
.. [1] A. C. Popescu, H. Farid, Exposing digital forgeries in color filter
   array interpolated images, IEEE Trans. Signal Processing 53(10), 2005.
.. [2] H. R. Chennamma, L. Rangarajan, Image splicing detection using
   inherent lens radial distortion, IJCSI 7(6), 2010 (the radial model).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from forensics_core import RadialResampling

from .significance import log10_binom_tail

#: A block's parity is predicted when this share of its sampled pixels agree on it.
DECISIVE_SHARE = 0.8
#: The mosaic follows the warp when agreement this unlikely by chance is seen (log10 of the binomial tail).
MAX_LOG10_P = -6.0
#: The profile is refitted to the mosaic within this share of each term, plus :data:`_FIT_MIN_PX` pixels.
_FIT_SPAN = 0.1
_FIT_MIN_PX = 0.5
#: Values per term on each of the two grids of the refit.
_FIT_STEPS = 21
#: Voting blocks the refit scores at most (evenly spread), to bound its memory on large photos.
_FIT_BLOCKS = 12000
#: Pixels sampled along each side of a block (evenly spread) to predict its parity.
_SAMPLES = 4
#: Without a warp from jpeg_grid, one-term profiles ``D = a (r / R)^3`` searched, |a| up to this share of the half
#: diagonal (beyond the corner displacement of any lens correction of k1 up to about 0.2), in steps of ``_SEARCH_STEP_PX``.
SEARCH_MAX_SHARE = 0.08
_SEARCH_STEP_PX = 0.25
#: A warp the mosaic itself proposes must account for its other-diagonal blocks: at least this share of the
#: decisive blocks it moves by an odd sum vote for the other diagonal, and of those voting so, it moved that share.
SEARCH_MIN_PRECISION = 0.5
SEARCH_MIN_RECALL = 0.5


@dataclass(frozen=True)
class MosaicWarp:
    """How the photo's mosaic follows a radial warp.

    Attributes
    ----------
    other_diagonal, red_blue : ndarray of float, shape (ny, nx)
        Per block, the share of its sampled pixels that the warp moved onto
        the other diagonal from the photo's own phase, and onto its own
        diagonal with red and blue swapped.
    agree, votes : int
        Blocks whose vote matches a decisive prediction, of those voting with one.
    null_rate : float
        Their agreement expected by chance from the two maps' shares.
    log10_p : float
        Binomial tail of ``agree``, multiplied by the profiles tried in
        :func:`fitted` and the two choices of the photo's own diagonal.
    terms : (float, float)
        The warp's profile ``(a, b)``, pixels, as the mosaic fits it.
    follows : bool
        ``log10_p`` at most :data:`MAX_LOG10_P`.
    """

    other_diagonal: np.ndarray
    red_blue: np.ndarray
    agree: int
    votes: int
    null_rate: float
    log10_p: float
    terms: tuple[float, float] = (0.0, 0.0)

    @property
    def follows(self) -> bool:
        return self.log10_p <= MAX_LOG10_P

    def agreement(self, t_diag: np.ndarray, voting: np.ndarray) -> tuple[int, int]:
        """Blocks among ``voting`` (boolean, shape (ny, nx)) whose diagonal vote matches a decisive prediction, and
        how many had one."""
        share = self.other_diagonal
        decisive = voting & _decisive(share)
        return int(((t_diag[decisive] < 0) == (share[decisive] > 0.5)).sum()), int(decisive.sum())

    def questions(self, t_diag: np.ndarray, t_rb: np.ndarray, diag_voting: np.ndarray,
                  rb_voting: np.ndarray) -> tuple[tuple[str, np.ndarray, np.ndarray], ...]:
        """The region scan's two questions asked against the phase the warp gave each block.

        Returns ``(kind, disagree, voting)`` for ``"diagonal"`` and
        ``"red_blue"``, boolean arrays of shape (ny, nx): a block votes where
        it voted before and the warp's prediction for it is decisive, and
        disagrees where its vote is not the predicted one. Red and blue are
        asked of blocks on the photo's own diagonal, as without a warp.
        """
        other = self.other_diagonal > 0.5
        diagonal = diag_voting & _decisive(self.other_diagonal)
        red_blue = rb_voting & diagonal & ~other & _decisive(self.red_blue)
        return (("diagonal", (t_diag < 0) != other, diagonal),
                ("red_blue", (t_rb < 0) != (self.red_blue > 0.5), red_blue))

    def record(self) -> dict[str, object]:
        return {"agree": self.agree, "votes": self.votes, "null_rate": round(self.null_rate, 4),
                "log10_p": round(self.log10_p, 2), "profile_terms_px": [round(t, 2) for t in self.terms],
                "rule": (f"the warp's profile refitted to the blocks' diagonal votes (within {100 * _FIT_SPAN:g} % "
                         "of each term), its displacement rounded at each pixel gives them a phase, and their votes "
                         f"agree with it more often than by chance (p at most 1e{MAX_LOG10_P:g}, on blocks where at "
                         f"least {100 * DECISIVE_SHARE:g} % of the pixels agree on the parity); regions are then those "
                         "that depart from that phase")}


def _decisive(share: np.ndarray) -> np.ndarray:
    return (share >= DECISIVE_SHARE) | (share <= 1.0 - DECISIVE_SHARE)


def shift_parities(warp: RadialResampling, grid: tuple[int, int], block: int, shape: tuple[int, int]) -> np.ndarray:
    """Per block, the share of its pixels whose displacement, rounded per coordinate, has each parity.

    Parameters
    ----------
    warp : RadialResampling
    grid : (ny, nx)
        Blocks of the detector's grid.
    block : int
        Block side, pixels.
    shape : (H, W)
        The stored grid's size, pixels.

    Returns
    -------
    ndarray of float, shape (ny, nx, 4)
        Shares of ``(sy mod 2, sx mod 2)`` = (0, 0), (0, 1), (1, 0), (1, 1),
        the order of :data:`.votes.SHIFTS`, estimated on :data:`_SAMPLES` x
        :data:`_SAMPLES` pixels of each block.
    """
    ny, nx = grid
    offsets = (np.arange(_SAMPLES) * block) // _SAMPLES + block // (2 * _SAMPLES)
    ys = (np.arange(ny)[:, None] * block + offsets[None, :]).reshape(ny, 1, _SAMPLES, 1)
    xs = (np.arange(nx)[:, None] * block + offsets[None, :]).reshape(1, nx, 1, _SAMPLES)
    dy, dx = warp.displacement(ys, xs, shape)
    parity = (2 * (np.rint(dy) % 2) + np.rint(dx) % 2).astype(np.intp)
    return np.stack([(parity == c).mean(axis=(2, 3)) for c in range(4)], axis=2)


def _voting_sample(t_diag: np.ndarray, voting: np.ndarray, block: int, shape: tuple[int, int]):
    """The voting blocks' centres (at most :data:`_FIT_BLOCKS`, evenly spread) as the profile searches score them.

    Returns ``((dy_a, dx_a), (dy_b, dx_b), observed)``, each of shape (1, n):
    the displacement of each term of the profile at unit size, and whether
    the block votes for the other diagonal; None when no block votes.
    """
    ys, xs = np.nonzero(voting)
    if ys.size == 0:
        return None
    if ys.size > _FIT_BLOCKS:
        pick = np.linspace(0, ys.size - 1, _FIT_BLOCKS).astype(np.intp)
        ys, xs = ys[pick], xs[pick]
    centres = (ys * block + block / 2.0, xs * block + block / 2.0)
    terms = [tuple(np.asarray(v)[None, :] for v in RadialResampling(*unit).displacement(*centres, shape))
             for unit in ((1.0, 0.0), (0.0, 1.0))]
    return terms[0], terms[1], (t_diag[ys, xs] < 0)[None, :]


def fitted(warp: RadialResampling, t_diag: np.ndarray, voting: np.ndarray, block: int,
           shape: tuple[int, int]) -> RadialResampling:
    """The profile near ``warp``'s whose rounded displacement best matches the blocks' diagonal votes.

    A block's parity changes where ``D`` crosses a half-integer, so a profile
    a tenth of a pixel off (as one fitted to the JPEG grid's shifts modulo 8
    can be, far from the centre) puts whole bands of blocks on the wrong
    diagonal where ``D`` varies slowly. The mosaic marks those crossings
    itself: ``(a, b)`` is searched within :data:`_FIT_SPAN` of each term
    (relative), on a grid of :data:`_FIT_STEPS` values per term and then on
    a grid as fine around the best, for the most blocks whose vote matches
    the parity at their centre (either diagonal taken as the photo's own).
    """
    sample = _voting_sample(t_diag, voting, block, shape)
    if sample is None:
        return warp
    (dy0, dx0), (dy1, dx1), observed = sample
    n = observed.size
    a, b = warp.a, warp.b
    span_a, span_b = _FIT_SPAN * abs(a) + _FIT_MIN_PX, _FIT_SPAN * abs(b) + _FIT_MIN_PX
    for _ in range(2):
        grid_a, grid_b = np.meshgrid(np.linspace(a - span_a, a + span_a, _FIT_STEPS),
                                     np.linspace(b - span_b, b + span_b, _FIT_STEPS))
        ta, tb = grid_a.reshape(-1, 1), grid_b.reshape(-1, 1)
        odd = (np.rint(ta * dy0 + tb * dy1) + np.rint(ta * dx0 + tb * dx1)) % 2 != 0
        agree = (odd == observed).sum(axis=1)
        score = np.maximum(agree, n - agree)
        best = int(np.argmax(score))
        a, b = float(ta[best, 0]), float(tb[best, 0])
        span_a, span_b = 2.0 * span_a / (_FIT_STEPS - 1), 2.0 * span_b / (_FIT_STEPS - 1)
    return RadialResampling(a, b)


def searched(t_diag: np.ndarray, voting: np.ndarray, block: int,
             shape: tuple[int, int]) -> tuple[RadialResampling, int] | None:
    """The one-term radial warp whose rounded displacement best matches the blocks' diagonal votes, and how many
    profiles were tried.

    Where jpeg_grid establishes no warp (the first compression's grid did
    not survive, or survives in one band only), a lens correction that keeps
    the frame's scale at the centre (``cv2.undistort``'s default, no zoom)
    still moves the mosaic by ``D(r) = a (r / R)^3``, rounded at each pixel
    (paper eqs. 1-5: the one-term radial model), and leaves arcs of the
    other diagonal about each axis where ``D`` rounds to an odd sum. As
    ``D`` and ``-D`` round to the same parities, the mosaic shows the
    displacement's size, not whether the correction pushed pixels outwards
    or inwards: ``a`` is searched positive. The
    profiles ``a`` from 1 px to :data:`SEARCH_MAX_SHARE` of the half
    diagonal ``R`` are tried in steps of :data:`_SEARCH_STEP_PX` on the
    voting blocks' centres (at most :data:`_FIT_BLOCKS`), scored as
    :func:`fitted` scores them; :func:`mosaic_warp` then refits both terms
    and tests the best, its Bonferroni factor multiplied by the profiles
    tried here.

    Returns
    -------
    (RadialResampling, int) or None
        None when no block votes.
    """
    sample = _voting_sample(t_diag, voting, block, shape)
    if sample is None:
        return None
    (dy0, dx0), _, observed = sample
    half_diagonal = float(np.hypot(*shape)) / 2.0
    # A displacement and its opposite round to the same parities: the mosaic shows D's size, not its direction.
    candidates = np.arange(1.0, SEARCH_MAX_SHARE * half_diagonal, _SEARCH_STEP_PX)
    best_a, best_score = 0.0, -1
    for chunk in np.array_split(candidates, max(1, candidates.size // 128)):
        a = chunk[:, None]
        odd = (np.rint(a * dy0) + np.rint(a * dx0)) % 2 != 0
        agree = (odd == observed).sum(axis=1)
        score = np.maximum(agree, observed.size - agree)
        k = int(np.argmax(score))
        if score[k] > best_score:
            best_a, best_score = float(chunk[k]), int(score[k])
    return RadialResampling(best_a, 0.0), int(candidates.size)


def accounts_for(mosaic: MosaicWarp, t_diag: np.ndarray, voting: np.ndarray) -> bool:
    """Whether a warp the mosaic proposed accounts for its other-diagonal blocks, not only agrees beyond chance.

    Agreement beyond the chance the two maps' shares give is met by any
    overlap of structure: a pasted piece of the other diagonal crossed by
    one arc of a profile agrees more than chance. A lens correction moves
    the mosaic onto the other diagonal in arcs throughout, so most of the
    decisive blocks it moves by an odd sum vote for the other diagonal
    (precision at least :data:`SEARCH_MIN_PRECISION`), and most of those
    voting so lie where it moved them (recall at least
    :data:`SEARCH_MIN_RECALL`); a piece fills only part of an arc.
    """
    decisive = voting & _decisive(mosaic.other_diagonal)
    predicted = decisive & (mosaic.other_diagonal > 0.5)
    voted = decisive & (t_diag < 0)
    both = int((predicted & voted).sum())
    return bool(predicted.any() and voted.any() and both >= SEARCH_MIN_PRECISION * predicted.sum()
                and both >= SEARCH_MIN_RECALL * voted.sum())


def mosaic_warp(warp: RadialResampling, t_diag: np.ndarray, voting: np.ndarray, block: int,
                shape: tuple[int, int], tried: int = 1) -> MosaicWarp:
    """Whether the blocks' diagonal votes follow the warp, and where it puts the other diagonal.

    Parameters
    ----------
    warp : RadialResampling
    t_diag : ndarray of float, shape (ny, nx)
        The blocks' diagonal discriminant (negative: the other diagonal).
    voting : ndarray of bool, shape (ny, nx)
        Blocks that vote on the diagonal.
    block : int
        Block side, pixels.
    shape : (H, W)
        The stored grid's size, pixels.
    tried : int
        Profiles tried before ``warp`` was chosen (:func:`searched`), for the
        Bonferroni factor; 1 for a warp jpeg_grid established.
    """
    warp = fitted(warp, t_diag, voting, block, shape)
    parities = shift_parities(warp, t_diag.shape, block, shape)
    odd = parities[..., 1] + parities[..., 2]
    decisive = voting & _decisive(odd)
    best = None
    for own in ((0, 3), (1, 2)):
        # The photo's own phase is its majority's: the unmoved centre's, or the one most blocks were moved to.
        c0 = max(own, key=lambda c: float(parities[..., c][voting].sum()))
        other = 1.0 - odd if c0 in (1, 2) else odd
        candidate = MosaicWarp(other, parities[..., c0 ^ 3], 0, 0, 0.5, 0.0)
        k, n = candidate.agreement(t_diag, voting)
        p_obs = float((t_diag[decisive] < 0).mean()) if n else 0.0
        p_pred = float((candidate.other_diagonal[decisive] > 0.5).mean()) if n else 0.0
        rate = min(max(p_obs * p_pred + (1 - p_obs) * (1 - p_pred), 1e-9), 1 - 1e-9)
        tail = float(log10_binom_tail(np.array([k]), np.array([n]), rate)[0]) if n else 0.0
        # Bonferroni over the profiles tried and the two choices of the photo's own diagonal.
        log10_p = tail + np.log10(2.0 * _FIT_STEPS**2 * 2 * tried)
        if best is None or log10_p < best.log10_p:
            best = MosaicWarp(candidate.other_diagonal, candidate.red_blue, k, n, rate, float(min(0.0, log10_p)),
                              (warp.a, warp.b))
    return best
