"""SIFT keypoints of a photo matched against themselves: the candidate copies.

A copied region brings its keypoints with it, so a keypoint whose descriptor
is much closer to another keypoint of the same photo than to any third one
marks a candidate copy. The generalised 2NN test (g2NN) of Amerini et al.
[1]_ keeps, for each keypoint, its nearest neighbours up to the first large
jump in descriptor distance, so a region copied several times yields all its
copies.

References
----------
.. [1] I. Amerini, L. Ballan, R. Caldelli, A. Del Bimbo, G. Serra, A SIFT-based
   forensic method for copy-move attack detection and transformation recovery,
   IEEE Trans. Information Forensics and Security 6(3), 2011, pp. 1099-1110
   (sec. III-A, eq. 1).
.. [2] D. G. Lowe, Distinctive image features from scale-invariant keypoints,
   International Journal of Computer Vision 60(2), 2004, pp. 91-110.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

# Neighbours examined per keypoint: a region copied more than this many
# times keeps only its nearest copies.
_NEIGHBOURS = 10


@dataclass(frozen=True)
class SelfMatches:
    """Pairs of matching keypoints of one photo.

    Attributes
    ----------
    pairs : ndarray, shape (n, 4)
        ``(x1, y1, x2, y2)`` of each pair, work-image pixels; each unordered
        pair once.
    n_keypoints : int
        Keypoints found in the work image.
    """

    pairs: np.ndarray
    n_keypoints: int


def work_image(luma: np.ndarray, max_pixels: float) -> tuple[np.ndarray, float]:
    """The luma as 0-255 float32, reduced by area averaging to at most ``max_pixels``.

    Parameters
    ----------
    luma : ndarray, shape (H, W)
        In [0, 1].
    max_pixels : float

    Returns
    -------
    gray : ndarray, shape (h, w), float32
    scale : float
        ``h / H`` (1 when not reduced).
    """
    gray = np.clip(np.asarray(luma, dtype=np.float32), 0.0, 1.0) * 255.0
    scale = min(1.0, float(np.sqrt(max_pixels / gray.size)))
    if scale < 1.0:
        size = (max(1, round(gray.shape[1] * scale)), max(1, round(gray.shape[0] * scale)))
        gray = cv2.resize(gray, size, interpolation=cv2.INTER_AREA)
        scale = gray.shape[0] / luma.shape[0]
    return gray, scale


def self_matches(gray: np.ndarray, ratio: float, min_distance_px: float, max_keypoints: int) -> SelfMatches:
    """Keypoint pairs passing the g2NN test, at least ``min_distance_px`` apart.

    Parameters
    ----------
    gray : ndarray, shape (h, w)
        0-255.
    ratio : float
        g2NN threshold on ``d_i / d_(i+1)`` ([1]_ uses 0.5).
    min_distance_px : float
        Pairs closer than this are the same structure seen twice by SIFT,
        not a copy.
    max_keypoints : int
        The strongest keypoints kept (SIFT's ``nfeatures``), which bounds the
        cost of the all-pairs matching.
    """
    sift = cv2.SIFT_create(nfeatures=int(max_keypoints))
    keypoints, descriptors = sift.detectAndCompute(np.clip(gray, 0, 255).astype(np.uint8), None)
    n = len(keypoints)
    if descriptors is None or n < 3:
        return SelfMatches(np.zeros((0, 4), np.float32), n)
    xy = np.array([k.pt for k in keypoints], dtype=np.float32)
    k = min(_NEIGHBOURS + 1, n)
    knn = cv2.BFMatcher(cv2.NORM_L2).knnMatch(descriptors, descriptors, k=k)
    dist = np.array([[m.distance for m in row] for row in knn], dtype=np.float64)
    index = np.array([[m.trainIdx for m in row] for row in knn], dtype=np.intp)
    # Column 0 is the keypoint itself; neighbour j (1-based) is kept while
    # every ratio d_1/d_2 ... d_j/d_(j+1) stays below the threshold (eq. 1 of [1]).
    passes = dist[:, 1:-1] < ratio * dist[:, 2:]
    keep = np.cumprod(passes, axis=1).astype(bool)
    rows, cols = np.nonzero(keep)
    a, b = rows, index[rows, cols + 1]
    far = np.hypot(*(xy[a] - xy[b]).T) >= min_distance_px
    unique = {(int(min(i, j)), int(max(i, j))) for i, j in zip(a[far], b[far]) if i != j}
    if not unique:
        return SelfMatches(np.zeros((0, 4), np.float32), n)
    ij = np.array(sorted(unique), dtype=np.intp)
    return SelfMatches(np.hstack((xy[ij[:, 0]], xy[ij[:, 1]])), n)
