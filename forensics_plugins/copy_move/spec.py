"""What the copy_move detector declares: name, version, literature, parameters.

Kept apart from the method so that listing the plugins (``forensics plugins``,
``--help``) imports none of its numerical code.
"""

from __future__ import annotations

from typing import Any

from forensics_core import DetectorSpec

NAME = "copy_move"
#: How a candidate copy was found (``found_by`` of each of the finding's hypotheses).
KEYPOINTS = "keypoints"
GRAIN = "grain autocorrelation"
VERSION = "1.6.0"
REFERENCES = (
    "I. Amerini, L. Ballan, R. Caldelli, A. Del Bimbo, G. Serra, A SIFT-based forensic method for copy-move attack "
    "detection and transformation recovery, IEEE Trans. Information Forensics and Security 6(3), 2011, "
    "pp. 1099-1110.",
    "D. G. Lowe, Distinctive image features from scale-invariant keypoints, International Journal of Computer "
    "Vision 60(2), 2004, pp. 91-110.",
    "J. Fridrich, D. Soukal, J. Lukáš, Detection of copy-move forgery in digital images, Digital Forensic Research "
    "Workshop, 2003.",
    "M. A. Fischler, R. C. Bolles, Random sample consensus, Communications of the ACM 24(6), 1981, pp. 381-395.",
    "L. Moisan, P. Moulon, P. Monasse, Automatic homographic registration of a pair of images, with a contrario "
    "elimination of outliers, Image Processing On Line 2, 2012, pp. 56-73.",
    "D. Cozzolino, G. Poggi, L. Verdoliva, Efficient dense-field copy-move forgery detection, IEEE Trans. "
    "Information Forensics and Security 10(11), 2015, pp. 2284-2297.",
    "G. D. Evangelidis, E. Z. Psarakis, Parametric image alignment using enhanced correlation coefficient "
    "maximization, IEEE Trans. Pattern Analysis and Machine Intelligence 30(10), 2008, pp. 1858-1865.",
)
DEFAULT_PARAMS: dict[str, Any] = {
    "max_work_pixels": 2_000_000,
    "max_keypoints": 10_000,
    "min_keypoints": 50,
    "g2nn_ratio": 0.5,
    "min_distance_px": 16,
    "max_hypotheses": 4,
    "min_inliers": 5,
    "ransac_threshold_px": 3.0,
    "refine_max_shift_px": 4.0,
    "window_px": 16,
    "identical_window_peak": 0.2,
    "dense_smooth_ratio": 3.0,
    "dense_min_sigma": 6.0,
    "dense_threshold": 0.3,
    "dense_max_candidates": 4,
    "max_points_listed": 200,
}

SPEC = DetectorSpec(
    name=NAME,
    version=VERSION,
    description="Finds regions copied within the photo (SIFT matches under one similarity transform, and moves of "
                "smooth areas whose grain repeats) and measures "
                "whether they share their fine grain, which correlates sharply at the alignment as a copy's does, "
                "or only their structure, whose correlation persists along its edges as in a scene that repeats "
                "itself.",
    references=REFERENCES,
    default_params=DEFAULT_PARAMS,
    calibrated_on="score",
)
