"""What the noise detector declares: name, version, literature, parameters.

Kept apart from the method so that listing the plugins (``forensics plugins``,
``--help``) imports none of its numerical code.
"""

from __future__ import annotations

from typing import Any

from forensics_core import DetectorSpec

NAME = "noise"
VERSION = "1.0.0"
REFERENCES = (
    "B. Mahdian, S. Saic, Using noise inconsistencies for blind image forensics, Image and Vision Computing "
    "27(10), 2009, pp. 1497-1503.",
    "S. Lyu, X. Pan, X. Zhang, Exposing region splicing forgeries with blind local noise estimation, "
    "International Journal of Computer Vision 110(2), 2014, pp. 202-221.",
    "M. Gardella, P. Musé, J.-M. Morel, M. Colom, Noisesniffer: a fully automatic image forgery detector based "
    "on noise analysis, IEEE International Workshop on Biometrics and Forensics, 2021.",
    "D. L. Donoho, I. M. Johnstone, Ideal spatial adaptation by wavelet shrinkage, Biometrika 81(3), 1994, "
    "pp. 425-455 (the median absolute deviation as a noise scale).",
)
DEFAULT_PARAMS: dict[str, Any] = {
    "fine_min_order": 7,
    "coarse_max_order": 2,
    "energy_floor": 0.01,
    "clip_levels": [5, 250],
    "intensity_bins": 8,
    "texture_bins": 8,
    "min_cell_blocks": 10,
    "scale_floor": 0.1,
    "z_clip": 4.0,
    "window_fractions": [8, 5, 3],
    "min_window_blocks": 4,
    "min_valid_share": 0.5,
    "min_blocks": 256,
    "score_cap": 20.0,
    "list_threshold": 6.0,
    "max_windows_listed": 10,
}

SPEC = DetectorSpec(
    name=NAME,
    version=VERSION,
    description="Compares each region's fine-grain noise with that of like content (grey level, texture) "
                "elsewhere in the photo, as content pasted from another photo, resized or retouched rarely "
                "matches it.",
    references=REFERENCES,
    default_params=DEFAULT_PARAMS,
    calibrated_on="score",
)
