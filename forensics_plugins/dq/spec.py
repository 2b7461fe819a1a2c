"""What the dq detector declares: name, version, literature, parameters.

Kept apart from the method so that listing the plugins (``forensics plugins``,
``--help``) imports none of its numerical code.
"""

from __future__ import annotations

from typing import Any

from forensics_core import DetectorSpec

NAME = "dq"
VERSION = "1.0.0"
REFERENCES = (
    "T. Bianchi, A. Piva, Image forgery localization via block-grained analysis of JPEG artifacts, IEEE Trans. "
    "Information Forensics and Security 7(3), 2012, pp. 1003-1017.",
    "J. Lukáš, J. Fridrich, Estimation of primary quantization matrix in double compressed JPEG images, Proc. "
    "Digital Forensic Research Workshop, 2003.",
    "A. Desolneux, L. Moisan, J.-M. Morel, From Gestalt Theory to Image Analysis, Springer, 2008.",
)
DEFAULT_PARAMS: dict[str, Any] = {
    "n_frequencies": 15,
    "min_gain_nats": 10.0,
    "min_alpha": 0.6,
    "min_frequencies": 3,
    "clip_margin": 4.0,
    "vote_margin_nats": 1.0,
    "window_blocks": [6, 12, 24],
    "min_informative": 10,
    "score_cap": 20.0,
    "seed": 0,
    "max_windows_listed": 20,
}

SPEC = DetectorSpec(
    name=NAME,
    version=VERSION,
    description="Reads the stored DCT coefficients, estimates the quantisation of an earlier JPEG save and maps "
                "the blocks that do not carry it, as content pasted after that save does not.",
    references=REFERENCES,
    default_params=DEFAULT_PARAMS,
    formats=("JPEG", "MPO"),
    calibrated_on="score",
)
