"""What the prnu detector declares: name, version, literature, parameters.

Kept apart from the method so that listing the plugins imports none of its
numerical code.
"""

from __future__ import annotations

from typing import Any

from forensics_core import DetectorSpec

NAME = "prnu"
VERSION = "1.0.0"
REFERENCES = (
    "J. Lukáš, J. Fridrich, M. Goljan, Digital camera identification from sensor pattern noise, IEEE Transactions "
    "on Information Forensics and Security 1(2), 2006, pp. 205-214.",
    "M. Chen, J. Fridrich, M. Goljan, J. Lukáš, Determining image origin and integrity using sensor noise, IEEE "
    "Transactions on Information Forensics and Security 3(1), 2008, pp. 74-90.",
    "M. Goljan, J. Fridrich, Camera identification from cropped and scaled images, Proc. SPIE 6819, 2008.",
    "G. Chierchia, G. Poggi, C. Sansone, L. Verdoliva, A Bayesian-MRF approach for PRNU-based image forgery "
    "detection, IEEE Transactions on Information Forensics and Security 9(4), 2014, pp. 554-567.",
    "M. K. Mihcak, I. Kozintsev, K. Ramchandran, Spatially adaptive statistical modeling of wavelet image "
    "coefficients and its application to denoising, ICASSP 1999, pp. 3253-3256.",
)
DEFAULT_PARAMS: dict[str, Any] = {
    "sigma0": 3.0,
    "block": 256,
    "region_llr": 8.0,
    "min_pce": 60.0,
}
SPEC = DetectorSpec(
    name=NAME,
    version=VERSION,
    description="Sensor fingerprint (PRNU): was the photo taken by the reference camera, and does every part of it "
                "carry that camera's fingerprint?",
    references=REFERENCES,
    default_params=DEFAULT_PARAMS,
    uses_reference=True,
)
