"""What the jpeg_grid detector declares: name, version, literature, parameters.

Kept apart from the method so that listing the plugins (``forensics plugins``,
``--help``) imports none of its numerical code.
"""

from __future__ import annotations

from typing import Any

from forensics_core import DetectorSpec

NAME = "jpeg_grid"
VERSION = "2.6.0"

REFERENCES = (
    "T. Nikoukhah, J. Anger, T. Ehret, M. Colom, J.-M. Morel, R. Grompone von Gioi, JPEG Grid Detection based on "
    "the Number of DCT Zeros and its Application to Automatic and Localized Forgery Detection, IEEE/CVF CVPR "
    "Workshops, 2019, pp. 110-118.",
    "T. Nikoukhah, J. Anger, M. Colom, J.-M. Morel, R. Grompone von Gioi, ZERO: a Local JPEG Grid Origin Detector "
    "Based on the Number of DCT Zeros and its Applications in Image Forensics, Image Processing On Line 11 (2021), "
    "pp. 396-433, doi:10.5201/ipol.2021.390.",
    "A. Desolneux, L. Moisan, J.-M. Morel, From Gestalt Theory to Image Analysis: A Probabilistic Approach, "
    "Springer, 2008.",
)

DEFAULT_PARAMS: dict[str, Any] = {
    "missing_grid": True,
    "missing_method": "lattice",
    "recompress_quality": 99,
    "nfa_threshold": 1.0,
    "cell": 8,
    "map_max_side": 96,
    "max_regions_listed": 8,
}

SPEC = DetectorSpec(
    name=NAME,
    version=VERSION,
    description="Finds the photo's 8x8 JPEG block grid from the zeros of the DCT (ZERO) and the regions whose grid "
                "is shifted or missing.",
    references=REFERENCES,
    default_params=DEFAULT_PARAMS,
    # Lossy WebP (VP8), HEIF (HEVC) and AVIF (AV1) code in blocks of their own
    # (4x4 to 64x64) and filter across them; ZERO's null was checked on JPEG
    # and lossless files only.
    formats=("JPEG", "MPO", "PNG", "TIFF"),
)
