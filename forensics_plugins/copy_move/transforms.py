"""Pairs of regions related by one similarity transform: the copy and its source.

A copy-move moves a region, often rotating and scaling it; its matched
keypoints then all obey one similarity transform (rotation, uniform scale,
translation), which RANSAC finds among the matches [1]_, [2]_. After each
transform its inliers are removed and the next is sought, so several copies
are found in turn.

Each transform's matches get the a-contrario number of false alarms of
AC-RANSAC [4]_: with ``n`` pairs left to explain, ``k`` of them within
``eps`` pixels of where the transform puts them, and ``alpha = 2 pi eps^2 /
area`` the chance that a pair with its second point placed at random (and
either side taken as the source) lands within ``eps``,

    NFA = (n - 2) C(n, k) C(k, 2) alpha^(k - 2),

the expected number of transforms explaining as many pairs by chance. It
tells matches that agree from a chance alignment of unrelated keypoints; a
scene that repeats itself agrees as well as a copy does, which is for the
grain test (:mod:`.identity`) to tell apart.

Keypoint positions fix a transform to a fraction of a pixel at best; over a
scaled or rotated copy the error grows across the region, enough to
misalign the fine grain the copy shares with its source. :func:`refine`
therefore aligns the regions' intensities themselves, by maximising their
enhanced correlation coefficient (ECC) [3]_ from the RANSAC estimate.

References
----------
.. [1] M. A. Fischler, R. C. Bolles, Random sample consensus, Communications
   of the ACM 24(6), 1981, pp. 381-395.
.. [2] I. Amerini, L. Ballan, R. Caldelli, A. Del Bimbo, G. Serra, A SIFT-based
   forensic method for copy-move attack detection and transformation recovery,
   IEEE TIFS 6(3), 2011 (sec. III-C).
.. [3] G. D. Evangelidis, E. Z. Psarakis, Parametric image alignment using
   enhanced correlation coefficient maximization, IEEE TPAMI 30(10), 2008,
   pp. 1858-1865.
.. [4] L. Moisan, P. Moulon, P. Monasse, Automatic homographic registration of
   a pair of images, with a contrario elimination of outliers, IPOL 2, 2012,
   pp. 56-73 (after L. Moisan, B. Stival, IJCV 57(3), 2004).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.special import gammaln


@dataclass(frozen=True)
class Hypothesis:
    """One candidate copy: ``target = matrix @ (source, 1)``.

    Attributes
    ----------
    matrix : ndarray, shape (2, 3)
        Similarity transform from source to target, work-image pixels.
    source, target : ndarray, shape (n, 2)
        The inlier keypoints on each side, work-image pixels.
    log10_nfa : float
        ``log10`` of the matches' number of false alarms (module docstring);
        NaN for a candidate not found by keypoints.
    """

    matrix: np.ndarray
    source: np.ndarray
    target: np.ndarray
    log10_nfa: float = float("nan")

    @property
    def scale(self) -> float:
        return float(np.hypot(self.matrix[0, 0], self.matrix[1, 0]))

    @property
    def rotation_deg(self) -> float:
        return float(np.degrees(np.arctan2(self.matrix[1, 0], self.matrix[0, 0])))

    @property
    def stretch(self) -> tuple[float, float, float]:
        """``(scale_x, scale_y, shear)`` of ``matrix[:, :2] = R(rotation_deg) @ [[scale_x, shear * scale_y],
        [0, scale_y]]``: equal scales and no shear for a similarity; the intensities' (affine) alignment
        (:func:`refine`) may stretch the copy unevenly."""
        a, b, c, d = self.matrix[0, 0], self.matrix[0, 1], self.matrix[1, 0], self.matrix[1, 1]
        scale_x = float(np.hypot(a, c))
        cos, sin = a / scale_x, c / scale_x
        scale_y = float(d * cos - b * sin)
        return scale_x, scale_y, float((b * cos + d * sin) / scale_y)

    def reversed(self) -> Hypothesis:
        """The same pairs read the other way round: ``source = inverse(matrix) @ (target, 1)``."""
        return Hypothesis(cv2.invertAffineTransform(self.matrix), self.target, self.source, self.log10_nfa)


def log10_nfa(n: int, k: int, threshold_px: float, area_px: float) -> float:
    """``log10`` of AC-RANSAC's number of false alarms for ``k`` of ``n`` pairs within ``threshold_px`` (module docstring)."""
    alpha = min(1.0, 2.0 * np.pi * threshold_px**2 / area_px)

    def log_choose(a: int, b: int) -> float:
        return float(gammaln(a + 1) - gammaln(b + 1) - gammaln(a - b + 1))

    return float((np.log(max(n - 2, 1)) + log_choose(n, k) + log_choose(k, 2) + (k - 2) * np.log(alpha)) / np.log(10))


def hypotheses(pairs: np.ndarray, max_models: int, min_inliers: int, threshold_px: float,
               area_px: float) -> list[Hypothesis]:
    """Similarity transforms explaining groups of keypoint pairs, strongest first.

    Parameters
    ----------
    pairs : ndarray, shape (n, 4)
        ``(x1, y1, x2, y2)``, unordered pairs.
    max_models : int
    min_inliers : int
        A transform needs at least this many pairs (a similarity has four
        degrees of freedom, two pairs fix it; more make it a finding).
    threshold_px : float
        RANSAC's reprojection tolerance.
    area_px : float
        The work image's area, for the matches' number of false alarms.

    Notes
    -----
    Each pair enters in both orientations, since which side is the copy is
    unknown; a pair counts for a transform in whichever orientation fits it.
    OpenCV's RANSAC draws from a generator with a fixed seed, so the result
    is reproducible.
    """
    out: list[Hypothesis] = []
    left = np.asarray(pairs, dtype=np.float32)
    for _ in range(max_models):
        if len(left) < min_inliers:
            break
        both = np.vstack((left, left[:, [2, 3, 0, 1]]))
        matrix, inliers = cv2.estimateAffinePartial2D(
            np.ascontiguousarray(both[:, :2]), np.ascontiguousarray(both[:, 2:]), method=cv2.RANSAC,
            ransacReprojThreshold=threshold_px, maxIters=5000, confidence=0.999, refineIters=10)
        if matrix is None:
            break
        inliers = inliers.ravel().astype(bool)
        n = len(left)
        forward, backward = inliers[:n], inliers[n:] & ~inliers[:n]
        used = forward | backward
        if used.sum() < min_inliers:
            break
        source = np.where(forward[:, None], left[:, :2], left[:, 2:])[used]
        target = np.where(forward[:, None], left[:, 2:], left[:, :2])[used]
        out.append(Hypothesis(matrix.astype(np.float64), source.astype(np.float64), target.astype(np.float64),
                              log10_nfa(n, int(used.sum()), threshold_px, area_px)))
        left = left[~used]
    return out


def refine(gray: np.ndarray, hypothesis: Hypothesis, region: np.ndarray, max_shift_px: float) -> Hypothesis | None:
    """The hypothesis with its transform aligned on the regions' intensities (ECC, affine), or None.

    Parameters
    ----------
    gray : ndarray, shape (h, w)
        Work image, 0-255.
    hypothesis : Hypothesis
    region : ndarray of bool, shape (h, w)
        The target region; its bounding box is the template aligned.
    max_shift_px : float
        A refinement that moves a corner of the target region's source by
        more than this (beyond 5 % of the region's size) is not a refinement
        of this hypothesis but another alignment, and None is returned. The
        refined transform is affine: editors also stretch a copy unevenly
        (MICC-F220's copies are scaled by different factors along x and y),
        which a similarity can only approximate.

    Returns
    -------
    Hypothesis or None
        None also when ECC does not converge.
    """
    ys, xs = np.nonzero(region)
    if len(xs) < 64:
        return None
    x0, x1, y0, y1 = int(xs.min()), int(xs.max()) + 1, int(ys.min()), int(ys.max()) + 1
    template = np.ascontiguousarray(gray[y0:y1, x0:x1], dtype=np.float32)
    back = cv2.invertAffineTransform(hypothesis.matrix)
    # ECC warps template coordinates (in the box) to input coordinates: the
    # source, cut out with the margin a refinement may move it by, so that the
    # cost follows the region's size, not the photo's.
    warp = back.copy()
    warp[:, 2] = back[:, :2] @ np.array([x0, y0], dtype=np.float64) + back[:, 2]
    corners = np.array([[0, 0], [x1 - x0, 0], [0, y1 - y0], [x1 - x0, y1 - y0]], dtype=np.float64)
    limit = max_shift_px + 0.05 * max(x1 - x0, y1 - y0)
    source = corners @ warp[:, :2].T + warp[:, 2]
    h, w = gray.shape
    sx0, sy0 = (max(0, int(np.floor(v - limit - 2))) for v in source.min(axis=0))
    sx1, sy1 = min(w, int(np.ceil(source[:, 0].max() + limit + 2))), min(h, int(np.ceil(source[:, 1].max() + limit + 2)))
    if sx1 - sx0 < 8 or sy1 - sy0 < 8:
        return None
    start = warp.copy()
    start[:, 2] -= (sx0, sy0)
    try:
        _, found = cv2.findTransformECC(template, np.ascontiguousarray(gray[sy0:sy1, sx0:sx1], dtype=np.float32),
                                        start.astype(np.float32), cv2.MOTION_AFFINE,
                                        (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-5), None, 1)
    except cv2.error:
        return None
    found = found.astype(np.float64)
    found[:, 2] += (sx0, sy0)
    moved = np.abs((corners @ found[:, :2].T + found[:, 2]) - source).max()
    if moved > limit:
        return None
    refined_back = found.copy()
    refined_back[:, 2] = found[:, 2] - found[:, :2] @ np.array([x0, y0], dtype=np.float64)
    return Hypothesis(cv2.invertAffineTransform(refined_back), hypothesis.source, hypothesis.target,
                      hypothesis.log10_nfa)

