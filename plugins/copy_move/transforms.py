"""Pairs of regions related by one similarity transform: the copy and its source.

A copy-move moves a region, often rotating and scaling it; its matched
keypoints then all obey one similarity transform (rotation, uniform scale,
translation), which RANSAC finds among the matches [1]_, [2]_. After each
transform its inliers are removed and the next is sought, so several copies
are found in turn.

References
----------
.. [1] M. A. Fischler, R. C. Bolles, Random sample consensus, Communications
   of the ACM 24(6), 1981, pp. 381-395.
.. [2] I. Amerini, L. Ballan, R. Caldelli, A. Del Bimbo, G. Serra, A SIFT-based
   forensic method for copy-move attack detection and transformation recovery,
   IEEE TIFS 6(3), 2011 (sec. III-C).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class Hypothesis:
    """One candidate copy: ``target = matrix @ (source, 1)``.

    Attributes
    ----------
    matrix : ndarray, shape (2, 3)
        Similarity transform from source to target, work-image pixels.
    source, target : ndarray, shape (n, 2)
        The inlier keypoints on each side, work-image pixels.
    """

    matrix: np.ndarray
    source: np.ndarray
    target: np.ndarray

    @property
    def scale(self) -> float:
        return float(np.hypot(self.matrix[0, 0], self.matrix[1, 0]))

    @property
    def rotation_deg(self) -> float:
        return float(np.degrees(np.arctan2(self.matrix[1, 0], self.matrix[0, 0])))


def hypotheses(pairs: np.ndarray, max_models: int, min_inliers: int, threshold_px: float) -> list[Hypothesis]:
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
        out.append(Hypothesis(matrix.astype(np.float64), source.astype(np.float64), target.astype(np.float64)))
        left = left[~used]
    return out
