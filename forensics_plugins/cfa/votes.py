r"""Stage 2: each block's vote for the phase of the image's demosaicing pattern.

The image's own *signature* ``m`` is the profile of the residual features of
:mod:`.residuals` (F features at the 4 positions of the 2 x 2 cell) that its
blocks share, estimated robustly (Tukey's biweight, iteratively reweighted,
then again without the blocks that put green on the other diagonal) so that a
pasted minority does not pull it. Where red and blue are told apart,
the signature is allowed to vary linearly with the block's colour balance:
edge-aware demosaicing leaks the noise of the sampled channel into the
interpolated ones, so in a strongly red or blue area the red and blue sites
can trade their residual levels (measured: on a 12 MP Hamilton-Adams photo,
blocks redder than ``log(R/B) = 0.6`` voted against the photo's red and blue
sites more often than for them). A block whose mosaic is shifted by
``s = (dy, dx)`` relative to the rest of the image shows the signature with its
positions shifted: ``x[p] = m[p + s]``. Each block scores the four shifts with
Fisher's linear discriminant under a covariance shared by the shifts,

.. math::  S_s(x) = x^\top \Sigma^{-1} \mu_s, \qquad \mu_s[p] = m[p + s],

where :math:`\Sigma` is the covariance of the blocks' departures from the
signature, averaged over the four shifts (so no shift is favoured by the
covariance itself) and shrunk towards a multiple of the identity (Ledoit &
Wolf, 2004). Because the signature is learnt from the image, no demosaicing
algorithm is assumed: the sampled positions may be the noisier ones
(bilinear) or the smoother ones (Hamilton-Adams), and the features that
separate them are weighted by how well they do in this image. This is the
"pattern vote" of Bammey, Grompone von Gioi & Morel (2020, 2022) with a
learnt linear detector in place of their neural network.

Two binary questions are asked of every block, as in those papers:

* ``t_diag = max(S_00, S_11) - max(S_01, S_10)``: positive when the block's
  green lies on the same diagonal as the image's (shifts (0, 1) and (1, 0)
  move green to the other diagonal);
* ``t_rb = S_00 - S_11``, under the colour-dependent signature: positive
  when red and blue are where the image has them (a shift by (1, 1) swaps
  them).

The model a block is scored with is learnt from the other half of the blocks
(a checkerboard split), so under the null hypothesis of no mosaic trace a
block's features are independent of the model and exchangeable under the
shifts (the colour balance is unchanged by a shift), and by the symmetry of
the shared covariance each question is a fair coin (p = 1/2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .residuals import POSITIONS

SHIFTS = ((0, 0), (0, 1), (1, 0), (1, 1))
"""Shifts ``(dy, dx)`` of a block's mosaic relative to the image's, in score order."""

# _PERM[s][p]: index of position p + s (mod 2) in POSITIONS.
_PERM = np.array([[POSITIONS.index(((py + dy) % 2, (px + dx) % 2)) for py, px in POSITIONS] for dy, dx in SHIFTS])


@dataclass(frozen=True)
class PhaseVotes:
    """Scores and votes of every block.

    Attributes
    ----------
    scores : ndarray of float64, shape (ny, nx, 4)
        ``S_s`` for the shifts of :data:`SHIFTS` under the colour-independent
        signature; zero for unusable blocks.
    t_diag, t_rb : ndarray of float64, shape (ny, nx)
        The two discriminants (positive: agrees with the image); zero for
        unusable blocks.
    usable : ndarray of bool, shape (ny, nx)
        Blocks with enough unclipped texture to vote.
    signature : ndarray of float64, shape (F, 4)
        The image's signature (the mean of those learnt from the two halves),
        centred over positions.
    """

    scores: np.ndarray
    t_diag: np.ndarray
    t_rb: np.ndarray
    usable: np.ndarray
    signature: np.ndarray

    @property
    def shift_vote(self) -> np.ndarray:
        """Index into :data:`SHIFTS` of each block's answer to the two questions, -1 where unusable; shape (ny, nx).

        Green on the other diagonal: the better of (0, 1) and (1, 0); else
        (0, 0) or, when red and blue disagree, (1, 1).
        """
        other = np.where(self.scores[..., 1] >= self.scores[..., 2], 1, 2)
        same = np.where(self.t_rb < 0, 3, 0)
        return np.where(self.usable, np.where(self.t_diag < 0, other, same), -1)


_N_POS = len(POSITIONS)
_TUKEY_C = 2.0
MAX_TRAIN = 4000
"""Blocks a model is learnt from at most (evenly spread); more add little to 40 x 40 statistics."""


def _flat_perm(n_features: int) -> np.ndarray:
    """:data:`_PERM` on the flattened (feature, position) axis; shape (4, n_features * 4)."""
    base = np.arange(n_features)[:, None] * _N_POS
    return np.stack([(base + perm[None, :]).ravel() for perm in _PERM])


def _gram(a: np.ndarray, weight: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a^T diag(weight) b`` by einsum: these products are small, and a multi-threaded
    BLAS on a busy machine spends far longer waiting for its threads than computing them.
    Weighting ``a`` first makes it a two-operand product, three times faster than the
    three-operand einsum, with the same products summed in the same order."""
    return np.einsum("ni,nj->ij", a * weight[:, None], b)


def _design(colour: np.ndarray, usable: np.ndarray) -> np.ndarray:
    """Intercept and the robustly standardised colour balance, clipped to 4 deviations; shape (ny, nx, 2)."""
    c = colour.astype(np.float64)
    med = np.median(c[usable])
    mad = 1.4826 * np.median(np.abs(c[usable] - med))
    z = np.clip((c - med) / (mad if mad > 1e-6 else 1.0), -4.0, 4.0)
    return np.stack([np.ones_like(z), z], axis=2)


@dataclass(frozen=True)
class _Model:
    """A signature linear in the design row ``z`` of a block, and the precision of departures from it.

    ``coef`` has shape (k, F * 4): the profile of a block at shift (0, 0) is
    ``z @ coef`` (flattened feature-major); ``precision`` is (F * 4, F * 4).
    """

    coef: np.ndarray
    precision: np.ndarray

    def scores(self, x: np.ndarray, z: np.ndarray) -> np.ndarray:
        """``S_s`` of blocks ``x`` (n, F * 4) with design rows ``z`` (n, k) for every shift; shape (n, 4)."""
        y = np.einsum("nk,kl->nl", x, self.precision)
        m = np.einsum("nj,jk->nk", z, self.coef)
        perms = _flat_perm(x.shape[1] // _N_POS)
        return np.stack([np.einsum("nk,nk->n", y, m[:, perm]) for perm in perms], axis=1)


def _fit(train: np.ndarray, z: np.ndarray, shrinkage: float, ridge: float, rounds: int = 3) -> _Model:
    """Learn a signature model from some blocks by robust regression on their design rows.

    The blocks' features are regressed as they are, assuming most blocks
    share the image's phase: blocks of a pasted region depart from the fit
    and lose their weight (Tukey's biweight on the Mahalanobis norm of the
    departure, iteratively reweighted least squares). Aligning blocks by their
    voted shift instead would be circular: blocks whose signature resembles a
    shifted one for another reason (a strong colour cast under edge-aware
    demosaicing) would be learnt as shifted.

    Parameters
    ----------
    train : ndarray, shape (n, F, 4)
    z : ndarray, shape (n, k)
        Design rows, intercept first.
    shrinkage : float
        Weight in [0, 1] of the scaled identity in the covariance.
    ridge : float
        Ridge penalty on the slopes, relative to ``n``.
    rounds : int
        Reweighting rounds.

    Returns
    -------
    _Model
    """
    if len(train) > MAX_TRAIN:
        keep = np.linspace(0, len(train) - 1, MAX_TRAIN).round().astype(int)
        train, z = train[keep], z[keep]
    n, f, _ = train.shape
    d = f * _N_POS
    flat = train.reshape(n, d).astype(np.float64)
    perms = _flat_perm(f)
    penalty = ridge * n * np.diag([0.0] + [1.0] * (z.shape[1] - 1))
    weight = np.ones(n)
    for i in range(rounds + 1):
        coef = np.linalg.solve(_gram(z, weight, z) + penalty, _gram(z, weight, flat))
        dev = flat - np.einsum("nj,jk->nk", z, coef)
        # Averaging the covariance over the four shifts of the cell positions
        # makes it commute with them: no shift gains from the covariance alone.
        cov = _gram(dev, weight, dev) / weight.sum()
        cov = sum(cov[np.ix_(perm, perm)] for perm in perms) / len(perms)
        # The identity target commutes with the centring over positions, so the
        # directions the centred features never take stay out of the scores.
        target = np.eye(d) * np.trace(cov) / d
        precision = np.linalg.inv((1.0 - shrinkage) * cov + shrinkage * target)
        if i == rounds:
            break
        dist = np.sqrt(np.maximum(np.einsum("nk,kl,nl->n", dev, precision, dev, optimize=False), 0.0))
        # Tukey's biweight: blocks departing by more than twice the median
        # distance (a pasted region's, typically) get no weight at all.
        cutoff = _TUKEY_C * np.median(dist)
        weight = np.where(dist < cutoff, (1.0 - (dist / cutoff) ** 2) ** 2, 0.0)
    return _Model(coef, precision)


def _fit_plain(train: np.ndarray, z: np.ndarray, shrinkage: float, ridge: float,
               rounds: int = 2) -> tuple[_Model, np.ndarray]:
    """The colour-independent model, refitted without the blocks that put green on the other diagonal.

    Tukey's weights alone leave a pasted region's blocks some weight when
    their departure is moderate (edge-aware demosaicing), and half the
    region then votes with the photo. In the originals measured, blocks put
    their green on the other diagonal at random, never as a group for a
    reason of content (unlike red and blue, see the module notes), so
    dropping them from the training costs nothing there. The diagonal
    question keeps one signature for all colours: a colour slope fitted to a
    pasted area of distinctive colour would carry its shift to every block of
    that colour.

    Returns
    -------
    model : _Model
    keep : ndarray of bool, shape (n,)
        The training blocks whose green is on the model's diagonal.
    """
    keep = np.ones(len(train), dtype=bool)
    flat = train.reshape(len(train), -1).astype(np.float64)
    for _ in range(rounds):
        model = _fit(train[keep], z[keep], shrinkage, ridge)
        s = model.scores(flat, z)
        agree = np.maximum(s[:, 0], s[:, 3]) > np.maximum(s[:, 1], s[:, 2])
        if agree.sum() < 2 * train.shape[1] or np.array_equal(agree, keep):
            break
        keep = agree
    return model, keep


def phase_votes(features: np.ndarray, colour: np.ndarray, usable: np.ndarray, shrinkage: float,
                ridge: float) -> PhaseVotes:
    """Score every usable block against the signature learnt from the other half of the blocks.

    Parameters
    ----------
    features : ndarray, shape (ny, nx, F, 4)
        From :func:`.residuals.block_features`.
    colour : ndarray, shape (ny, nx)
        The blocks' colour balance (unchanged by a shift of the mosaic).
    usable : ndarray of bool, shape (ny, nx)
        Blocks allowed to vote and to train.
    shrinkage : float
        Covariance shrinkage towards a multiple of the identity, in [0, 1].
    ridge : float
        Ridge penalty of the colour slope, relative to the number of blocks.

    Returns
    -------
    PhaseVotes

    Raises
    ------
    ValueError
        When either half of the checkerboard has fewer usable blocks than
        twice the number of features (the discriminant cannot be learnt).
    """
    ny, nx, f, _ = features.shape
    flat = features.reshape(ny, nx, f * _N_POS)
    z = _design(colour, usable)
    half = (np.add.outer(np.arange(ny), np.arange(nx)) % 2).astype(bool)
    scores = np.zeros((ny, nx, 4))
    rb_scores = np.zeros((ny, nx, 4))
    signatures = []
    for part in (False, True):
        train = usable & (half != part)
        if train.sum() < 2 * f:
            raise ValueError(f"only {int(train.sum())} usable blocks to learn the signature from")
        sel = usable & (half == part)
        x = flat[sel].astype(np.float64)
        plain, keep = _fit_plain(features[train], z[train][:, :1], shrinkage, ridge)
        signatures.append(plain.coef[0])
        scores[sel] = plain.scores(x, z[sel][:, :1])
        rb_scores[sel] = _fit(features[train][keep], z[train][keep], shrinkage, ridge).scores(x, z[sel])
    t_diag = np.maximum(scores[..., 0], scores[..., 3]) - np.maximum(scores[..., 1], scores[..., 2])
    t_rb = rb_scores[..., 0] - rb_scores[..., 3]
    signature = np.mean(signatures, axis=0).reshape(f, _N_POS)
    return PhaseVotes(scores=scores, t_diag=np.where(usable, t_diag, 0.0), t_rb=np.where(usable, t_rb, 0.0),
                      usable=usable, signature=signature)
