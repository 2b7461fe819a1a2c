"""What the metadata detector declares: name, version, literature, parameters.

Kept apart from the method so that listing the plugins (``forensics plugins``,
``--help``) imports none of its numerical code.
"""

from __future__ import annotations

from typing import Any

from forensics_core import DetectorSpec

#: The detector whose global lens model the lens check reads.
LENS_DETECTOR = "lens_distortion"

NAME = "metadata"
VERSION = "1.2.0"

REFERENCES = (
    "CIPA DC-008-2019 / JEITA CP-3451E, Exchangeable image file format for digital still cameras: Exif Version 2.32, "
    "2019 (tags DateTime, DateTimeOriginal, Software, PixelXDimension, IFD1 thumbnail).",
    "ITU-T Rec. T.81 | ISO/IEC 10918-1, Digital compression and coding of continuous-tone still images, 1992, "
    "Annex K (example quantisation tables); Independent JPEG Group, libjpeg 6b/9, jcparam.c (quality scaling).",
    "H. Farid, Digital image ballistics from JPEG quantization, Dartmouth College TR2006-583, 2006.",
    "E. Kee, M. K. Johnson, H. Farid, Digital image authentication from JPEG headers, IEEE Trans. Information "
    "Forensics and Security 6(3), 1066-1075, 2011.",
    "E. Kee, H. Farid, Digital image authentication from thumbnails, Proc. SPIE 7541, Media Forensics and "
    "Security II, 2010 (thumbnails regenerated or left stale by editing; here the thumbnail's content is compared "
    "with the image's).",
    "ISO 16684-1:2019, Extensible metadata platform (XMP) specification, Part 1: Data model, serialization and "
    "core properties (xmp:CreatorTool, xmpMM:History with stEvt:softwareAgent).",
    "J. A. Nelder, R. Mead, A simplex method for function minimization, The Computer Journal 7(4), 308-313, 1965 "
    "(aligning the thumbnail with the part of the image it shows).",
    "M. Ayer, H. D. Brunk, G. M. Ewing, W. T. Reid, E. Silverman, An empirical distribution function for sampling "
    "with incomplete information, Ann. Math. Statist. 26(4), 641-647, 1955 (pool-adjacent-violators: the "
    "thumbnail's monotone tone curve).",
    "lensfun lens database (lensfun project, bundled with lensfunpy), CC BY-SA 3.0; distortion models poly3, poly5 "
    "and ptlens as documented in lensfun's lensfun.h.",
    "H. Dersch, Panorama Tools, radial lens correction with coefficients a, b, c (the ptlens model "
    "r_d = r_u (a r_u^3 + b r_u^2 + c r_u + 1 - a - b - c)).",
)

DEFAULT_PARAMS: dict[str, Any] = {
    "datetime_tolerance_s": 2.0,
    "own_table_makers": ["canon", "apple", "fujifilm"],
    "thumbnail_max_bytes": 262144,
    "thumbnail_max_pixels": 1048576,
    "thumbnail_aspect_tolerance": 0.03,
    "thumbnail_min_correlation": 0.95,
    "thumbnail_blur_px": 1.5,
    "thumbnail_change_threshold": 0.12,
    "thumbnail_max_region_fraction": 0.003,
    "lens_k1_tolerance": 0.02,
    "lens_alpha": 0.01,
    "lens_fit_grid": 64,
}

SPEC = DetectorSpec(
    name=NAME,
    version=VERSION,
    description="Runs the examiner's first metadata checks (EXIF, software, dates, size, thumbnail, JPEG tables, "
                "lens) and compares the lens the EXIF names with the measured distortion.",
    references=REFERENCES,
    default_params=DEFAULT_PARAMS,
    uses=(LENS_DETECTOR,),
)
