"""The prnu detector's likelihood ratios, from models fitted on real photos (``calibration.json``, :mod:`.calibrate`).

Two propositions, kept apart:

* Source. Hp: the photo was taken by the reference camera; Hd: by another
  camera of the same model. The score is the single-test z of the best
  alignment (:func:`.alignment.single_test_z`). Under Hd it is modelled by a
  Student t: centre and scale from real comparisons with other cameras'
  fingerprints, degrees of freedom from those with another unit of the same
  model (its tail is heavier than the normal the PCE theory gives, because
  cameras of one model share traces the filtering does not remove entirely);
  under Hp by a normal on ``ln z`` fitted on real photos of the reference
  camera.
* Manipulation. Hp: content was inserted into the photo from elsewhere; Hd:
  every part carries the camera's fingerprint. The score is the largest
  summed block log-likelihood ratio (:func:`.local.regions`), calibrated by
  lir's logistic regression on real splices and untouched photos.

Each is bounded by its ELUB bounds (Vergeer et al. 2016), computed by lir on
the calibration data.

References
----------
P. Vergeer, A. van Es, A. de Jongh, I. Alberink, R. Stoel, "Numerical
likelihood ratios outputted by LR systems are often based on extrapolation:
when to stop extrapolating?", Science & Justice 56(6), 2016, pp. 482-491.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from importlib.resources import files
from typing import Any

from scipy.stats import norm, t

CALIBRATION_FILE = "calibration.json"
_LN10 = math.log(10.0)


@dataclass(frozen=True)
class Models:
    """The fitted models and what they were fitted on (the ``calibration.json`` shipped with the plugin)."""

    attribution: dict[str, Any]
    manipulation: dict[str, Any]
    data: dict[str, Any]

    def attribution_log10_lr(self, z: float) -> float:
        """log10 LR for "taken by the reference camera" against "another camera of the same model", bounded."""
        a = self.attribution
        hd = t.logpdf(z, a["hd_df"], loc=a["hd_loc"], scale=a["hd_scale"])
        if z <= 0.0:
            hp = -math.inf
        else:
            hp = norm.logpdf(math.log(z), a["hp_mu"], a["hp_sigma"]) - math.log(z)
        value = (hp - hd) / _LN10 if hp > -math.inf else -math.inf
        return min(max(value, a["lower"]), a["upper"])

    def manipulation_log10_lr(self, score: float) -> float:
        """log10 LR for "content inserted" against "every part from the camera", bounded (never below LR 1's
        lower bound)."""
        m = self.manipulation
        return min(max(m["intercept"] + m["slope"] * score, m["lower"]), m["upper"])


@lru_cache(maxsize=1)
def shipped() -> Models | None:
    """The models shipped with the plugin, or None when the file is absent (the LRs are then not stated)."""
    path = files(__package__).joinpath(CALIBRATION_FILE)
    if not path.is_file():
        return None
    raw = json.loads(path.read_text(encoding="utf-8"))
    return Models(raw["attribution"], raw["manipulation"], raw["data"])
