r"""The content-matched null: how often blocks of a colour vote against the photo's phase anywhere in it.

The votes of :mod:`.votes` are a fair coin only where the photo carries no
trace at all. On real photos the residual profile of a block also depends on
what the block shows, through steps of the camera pipeline that act after
demosaicing: the colour matrix and white balance mix the channels with
weights set by the local colour, so in a saturated patch the noise of one
channel dominates the residuals of all three (Ramanath et al., 2005, sec.
IV); chroma denoising and 4:2:0 / 4:2:2 chroma subsampling rebuild the
colour differences on 2 x 2 (or 2 x 1) cells aligned with the Bayer cell
(ITU-T T.81 / JFIF), so the colour a block has decides how much of its
period-2 structure is the codec's rather than the sensor's. A signature
learnt from the whole photo then fits a strongly coloured area badly, and
its blocks vote against the photo's phase together, for the same reason,
although nothing was pasted (measured on an X-Rite chart: the saturated red
and magenta patches of an authentic camera JPEG voted against at rates of
0.87 and 0.88, for an NFA of 1e-103).

Under the content-matched null hypothesis a block votes against the photo's
phase with probability at most

.. math::  q_i = \max\left(\tfrac12, \hat r(c_i)\right),

where :math:`\hat r(c)` is the rate at which the voting blocks of the photo
whose chromaticity is near ``c`` disagree: a Nadaraya-Watson kernel
regression of the votes on the two chromaticity coordinates (``log R/B``
and the green excess), with a Gaussian kernel of :data:`BANDWIDTH` (a colour
difference of a few percent), evaluated on a histogram of the coordinates
(Wand & Jones, 1995, ch. 5, binned kernel estimators), and shrunk towards
1/2 by :data:`PRIOR_VOTES` votes so that a rare colour carries no weight
either way. A paste whose colours occur elsewhere in the photo is measured
against blocks of those colours that kept the photo's phase; a region whose
colour occurs nowhere else has its rate set by itself and is not flagged:
the votes cannot tell whether the colour or a paste turned it, and the
detector says so rather than guess. This is the background model of an
a-contrario test made to include what is explained without the structure
sought (Desolneux, Moisan & Morel, 2008, ch. 5).

References
----------
R. Ramanath, W. E. Snyder, Y. Yoo, M. S. Drew, Color image processing
pipeline, IEEE Signal Processing Magazine 22(1), 34-43, 2005.

ITU-T Recommendation T.81 (ISO/IEC 10918-1), Digital compression and coding
of continuous-tone still images, 1992, annex A.1.1 (component sampling).

A. Desolneux, L. Moisan, J.-M. Morel, From Gestalt Theory to Image Analysis:
A Probabilistic Approach, Springer, 2008.

M. P. Wand, M. C. Jones, Kernel Smoothing, Chapman & Hall, 1995.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

BANDWIDTH = 0.04
"""Kernel width in chromaticity units (natural log of a channel ratio)."""

PRIOR_VOTES = 8.0
"""Pseudo-votes at rate 1/2 added to every colour's kernel sums."""

_BINS_PER_BANDWIDTH = 2
_MAX_BINS = 256


def null_rates(disagree: np.ndarray, voting: np.ndarray, chroma: np.ndarray) -> np.ndarray:
    """Per-block probability of disagreeing under the content-matched null.

    Parameters
    ----------
    disagree, voting : ndarray of bool, shape (ny, nx)
        Blocks answering against the photo, and blocks answering at all.
    chroma : ndarray, shape (ny, nx, 2)
        The blocks' chromaticity coordinates.

    Returns
    -------
    ndarray of float64, shape (ny, nx)
        ``max(1/2, r(c))``: 1/2 wherever blocks of that colour agree with the
        photo's phase as a rule.
    """
    if not voting.any():
        return np.full(voting.shape, 0.5)
    c = chroma.reshape(-1, 2).astype(np.float64)
    lo = c[voting.ravel()].min(axis=0)
    step = BANDWIDTH / _BINS_PER_BANDWIDTH
    index = np.clip(np.floor((c - lo) / step).astype(np.int64), 0, _MAX_BINS - 1)
    shape = tuple(int(m) + 1 for m in index[voting.ravel()].max(axis=0))
    index = np.minimum(index, np.array(shape) - 1)
    flat = np.ravel_multi_index(index.T, shape)
    n = np.bincount(flat[voting.ravel()], minlength=shape[0] * shape[1]).reshape(shape).astype(np.float64)
    k = np.bincount(flat[(voting & disagree).ravel()], minlength=shape[0] * shape[1]).reshape(shape).astype(np.float64)
    # Kernel weights of peak 1 (not of unit sum), so the sums count the votes
    # within about a bandwidth and the prior weighs against those.
    area = 2.0 * np.pi * _BINS_PER_BANDWIDTH ** 2
    n = area * ndimage.gaussian_filter(n, _BINS_PER_BANDWIDTH, mode="constant")
    k = area * ndimage.gaussian_filter(k, _BINS_PER_BANDWIDTH, mode="constant")
    rate = (k + 0.5 * PRIOR_VOTES) / (n + PRIOR_VOTES)
    return np.maximum(0.5, rate.ravel()[flat]).reshape(voting.shape)
