"""What the lens_distortion detector declares: name, version, literature, parameters.

Kept apart from the method so that listing the plugins (``forensics plugins``,
``--help``) imports none of its numerical code.
"""

from __future__ import annotations

from typing import Any

from forensics_core import DetectorSpec

from .error_model import BOW_REL, CENTRE_SD, DOF, TAU_K1, TAU_PHOTO

#: What the synthetic generator makes (``forensics synth --kind``): an authentic
#: photo and the paper's three kinds of splice.
KINDS = ("authentic", "copy_move", "other_camera", "other_zoom")

NAME = "lens_distortion"
VERSION = "0.5.0"

REFERENCES = (
    "H. R. Chennamma, L. Rangarajan, Image splicing detection using inherent lens radial distortion, "
    "IJCSI 7(6), 2010.",
    "F. Devernay, A non-maxima suppression method for edge detection with sub-pixel accuracy, "
    "INRIA RR-2724, 1995.",
    "F. Devernay, O. Faugeras, Straight lines have to be straight, Machine Vision and Applications 13, 2001.",
    "L. Wasserman, A. Ramdas, S. Balakrishnan, Universal inference, PNAS 117(29), 2020.",
    "lensfun 0.3 lens database (distribution of real lenses' distortion), https://lensfun.github.io.",
)

DEFAULT_PARAMS: dict[str, Any] = {
    "sigma": 1.0,
    "min_length_fraction": 0.07,
    "max_lines": 150,
    "tolerance_px": 1.5,
    "max_k1": 0.35,
    "alpha": 0.01,
    "min_lines": 6,
    "single_lines": False,
    "paper_trim": True,
    "points_per_line": 48,
    # The error model of real lines, measured on authentic photos
    # (consistency module docstring); exposed for experiments, not for tuning.
    "tau_k1": TAU_K1,
    "bow_rel": BOW_REL,
    "dof": DOF,
    "tau_photo": TAU_PHOTO,
    "centre_sd": CENTRE_SD,
}

SPEC = DetectorSpec(
    name=NAME,
    version=VERSION,
    description="Checks that every straight line bends as one lens' radial distortion predicts.",
    references=REFERENCES,
    default_params=DEFAULT_PARAMS,
)
