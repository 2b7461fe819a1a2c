"""What the cfa detector declares: name, version, literature, parameters.

Kept apart from the method so that listing the plugins (``forensics plugins``,
``--help``) imports none of its numerical code.
"""

from __future__ import annotations

from typing import Any

from forensics_core import DetectorSpec

NAME = "cfa"
VERSION = "1.4.0"
#: Its lens-correction warp explains regions of the other diagonal (:mod:`forensics_plugins.cfa.warp`).
JPEG_GRID = "jpeg_grid"

REFERENCES = (
    "A. C. Popescu, H. Farid, Exposing digital forgeries in color filter array interpolated images, "
    "IEEE Transactions on Signal Processing 53(10), 3948-3959, 2005.",
    "M. Kirchner, Efficient estimation of CFA pattern configuration in digital camera images, "
    "Proc. SPIE 7541, Media Forensics and Security II, 754111, 2010.",
    "Q. Bammey, R. Grompone von Gioi, J.-M. Morel, An adaptive neural network for unsupervised mosaic "
    "consistency analysis in image forensics, CVPR 2020, 14194-14204.",
    "Q. Bammey, R. Grompone von Gioi, J.-M. Morel, Demosaicing to detect demosaicing and image forgeries, "
    "IEEE WIFS 2022.",
    "A. Desolneux, L. Moisan, J.-M. Morel, From Gestalt Theory to Image Analysis: A Probabilistic Approach, "
    "Springer, 2008 (a-contrario detection, number of false alarms).",
    "J. F. Hamilton Jr., J. E. Adams Jr., Adaptive color plan interpolation in single sensor color electronic "
    "camera, US Patent 5,629,734, 1997 (the edge-aware demosaicing of the validation).",
    "O. Ledoit, M. Wolf, A well-conditioned estimator for large-dimensional covariance matrices, "
    "Journal of Multivariate Analysis 88(2), 365-411, 2004.",
    "W. Hoeffding, On the distribution of the number of successes in independent trials, "
    "Annals of Mathematical Statistics 27(3), 713-721, 1956.",
    "R. Ramanath, W. E. Snyder, Y. Yoo, M. S. Drew, Color image processing pipeline, "
    "IEEE Signal Processing Magazine 22(1), 34-43, 2005.",
)

DEFAULT_PARAMS: dict[str, Any] = {
    "block_px": 16,
    "log_offset": 0.05,
    "max_clipped_fraction": 0.5,
    "min_activity": 0.2,
    "shrinkage": 0.05,
    "colour_ridge": 0.01,
    "min_usable_blocks": 64,
    "trace_alpha": 1e-3,
    "nfa_threshold": 0.01,
    "max_detectable_fraction": 0.10,
}

SPEC = DetectorSpec(
    name=NAME,
    version=VERSION,
    description="Finds regions whose demosaicing (colour filter array) phase disagrees with the rest of the photo.",
    references=REFERENCES,
    default_params=DEFAULT_PARAMS,
    # HEVC, AV1 and VP8 subsample chroma and filter across their blocks in
    # ways the null model (checked on camera JPEGs and lossless files) does
    # not describe.
    formats=("JPEG", "MPO", "PNG", "TIFF"),
    uses=(JPEG_GRID,),
)
