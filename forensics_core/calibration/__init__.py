"""Likelihood ratios for stated propositions: calibrators fitted on validation records (``forensics calibrate``).

:mod:`.model` applies them (no fitting library needed); :mod:`.fit` fits
them with NFI's ``lir`` and measures them (Cllr, Cllr_min) by
cross-validation grouped by scene.
"""

from .model import (
    FEATURE_CAP,
    HD,
    HP,
    CalibrationError,
    CalibrationSet,
    Calibrator,
    Fusion,
    feature,
    load,
    load_shipped,
    verbal,
)

__all__ = [
    "FEATURE_CAP",
    "HD",
    "HP",
    "CalibrationError",
    "CalibrationSet",
    "Calibrator",
    "Fusion",
    "feature",
    "load",
    "load_shipped",
    "verbal",
]
