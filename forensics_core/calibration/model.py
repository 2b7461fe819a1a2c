"""Calibrators as data: a detector's finding to a likelihood ratio, and the detectors' LRs to one fused LR.

Fitted by :mod:`.fit` (with NFI's ``lir``) on a validation record and stored
as JSON; applying them needs nothing but this module, so an examiner's run
does not depend on the fitting library.

The propositions (issue 13; ENFSI Guideline for Evaluative Reporting, 2015):

* Hp: after capture, content was inserted, moved or removed;
* Hd: the photo is as the camera produced it, with any recompression or
  resizing the findings describe.

A detector's LR is ``10 ** (a + b x)`` with ``x = -log10 p`` (its p-value,
or ``min(1, NFA)``, capped at :data:`FEATURE_CAP`), clipped to the ELUB
bounds of its calibration data (Vergeer et al. 2016): no LR claims more than
the validation data can support. A detector that states no test but a
measured ``score`` (e.g. copy_move's grain peak) is calibrated on
that score instead (``x = score``; the calibrator's ``feature`` says which).
Such a calibrator may be the four-parameter logistic of ``lir``
(``FourParameterLogisticCalibrator``), whose balanced posterior is

    P = c + (1 - c) / (1 + d) * sigmoid(ln 10 (a + b x)),   LR = P / (1 - P),

when its calibration data need the floor ``c`` (manipulations of another
kind score as originals do) or the ceiling ``d`` (scenes that mimic the
trace, such as printed repetition for copy-move); with ``c = d = 0`` it is
the logistic line. A one-sided calibrator (``lower = 0``) never supports Hd:
its detector's clean finding says nothing about the manipulations it cannot
see.
A detector that declines (status other than ``ok``, or no value of its
feature) gives LR = 1. The fused LR is a logistic-regression
fusion of the detectors' log10 LRs, ``c + sum(w_d llr_d)``, kept between the
sums of its negative and of its positive terms (the intercept ``c`` tempers
the detectors' evidence but creates none; :meth:`Fusion.log10_lr`) and
clipped to its own ELUB bounds; it learns how far the detectors repeat one
another instead of assuming they are independent.

References
----------
N. Brümmer, J. du Preez, Application-independent evaluation of speaker detection, Computer Speech and Language
20(2-3), 2006, pp. 230-275.
P. Vergeer, A. van Es, A. de Jongh, I. Alberink, R. Stoel, Numerical likelihood ratios outputted by LR systems are
often based on extrapolation: when to stop extrapolating?, Science & Justice 56(6), 2016, pp. 482-491.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from importlib.resources import files
from pathlib import Path
from typing import Any

FORMAT = "forensics-calibration/1"
SHIPPED = "real.json"
"""The calibrators shipped in ``forensics_core/calibration/`` (``make calibrate``)."""

# -log10 p above this carries no more evidence to a calibrator than the cap:
# a-contrario NFAs of 1e-600 are not a thousand times stronger evidence than
# 1e-30, and a logistic line must not be extrapolated that far.
FEATURE_CAP = 30.0
_P_FLOOR = 1e-300

HP = "after capture, content was inserted, moved or removed in part of the photo"
# Hd is what an examiner must hold against Hp: editors and platforms process whole photos, and a
# detector's null is checked on such photos (forensics validate innocent-processing), not on camera
# originals only.
HD = ("the photo is as the camera produced it, or that photo after processing of the whole frame that changes "
      "no content (recompression, resizing, cropping, rotation, lens or perspective correction, tone and colour "
      "adjustment, sharpening, noise reduction)")


class CalibrationError(Exception):
    """A calibration file cannot be read or does not fit this tool; one line for the user."""


def feature(p: float | None) -> float | None:
    """The calibrators' input, ``min(-log10 p, FEATURE_CAP)``; None for no p-value."""
    if p is None or not math.isfinite(p):
        return None
    return min(-math.log10(min(1.0, max(p, _P_FLOOR))), FEATURE_CAP)


def _clip(value: float, lower: float, upper: float) -> float:
    return min(max(value, lower), upper)


@dataclass(frozen=True)
class Calibrator:
    """One detector's score-to-LR map.

    Attributes
    ----------
    detector : str
    intercept, slope : float
        ``log10 LR = intercept + slope * x`` before bounding.
    lower, upper : float
        ELUB bounds, log10.
    n_hp, n_hd : int
        Calibration photos under each proposition on which the detector ran.
    n_declined_hp, n_declined_hd : int
        Those on which it declined (LR 1).
    cllr, cllr_min : float or None
        Cross-validated (grouped by scene) cost of the log-LRs over all
        calibration photos, declines included as LR 1, and its minimum after
        an ideal monotone recalibration.
    feature : str
        ``"p"``: ``x = -log10 p`` (:func:`feature`); ``"score"``: ``x`` is the
        finding's score, for detectors that state no p-value.
    floor, ceiling : float
        ``c`` and ``d`` of the four-parameter logistic (module docstring); 0
        for the logistic line.
    """

    detector: str
    intercept: float
    slope: float
    lower: float
    upper: float
    n_hp: int
    n_hd: int
    n_declined_hp: int = 0
    n_declined_hd: int = 0
    cllr: float | None = None
    cllr_min: float | None = None
    feature: str = "p"
    floor: float = 0.0
    ceiling: float = 0.0

    def x(self, p: float | None, score: float | None = None) -> float | None:
        """The calibrator's input from a finding's p-value and score; None when it has none."""
        if self.feature == "score":
            return None if score is None or not math.isfinite(score) else float(score)
        return feature(p)

    def log10_lr(self, p: float | None, score: float | None = None) -> float:
        """log10 LR for a finding's p-value and score (no value of the feature: the detector declined, LR 1)."""
        x = self.x(p, score)
        if x is None:
            return 0.0
        return _clip(four_parameter_log10_lr(x, self.intercept, self.slope, self.floor, self.ceiling),
                     self.lower, self.upper)


def four_parameter_log10_lr(x: float, intercept: float, slope: float, floor: float, ceiling: float) -> float:
    """log10 LR of the four-parameter logistic at ``x`` (module docstring); the line ``intercept + slope x`` when
    ``floor`` and ``ceiling`` are 0."""
    line = intercept + slope * x
    if floor == 0.0 and ceiling == 0.0:
        # Computed as the line itself: through P, a line far from 0 (x up to
        # FEATURE_CAP) would round P to 0 or 1.
        return line
    rise = 1.0 / (1.0 + 10.0 ** -line) if line > -300 else 0.0
    fall = 1.0 / (1.0 + 10.0 ** line) if line < 300 else 0.0
    hp = floor + (1.0 - floor) * rise / (1.0 + ceiling)
    hd = (1.0 - floor) * (ceiling + fall) / (1.0 + ceiling)
    if hp <= 0.0 or hd <= 0.0:
        return math.inf if hd <= 0.0 else -math.inf
    return math.log10(hp / hd)


@dataclass(frozen=True)
class Fusion:
    """Logistic-regression fusion of the detectors' log10 LRs.

    Attributes
    ----------
    intercept : float
    weights : dict of str to float
        Weight of each detector's log10 LR.
    lower, upper : float
        ELUB bounds of the fused log10 LR.
    cllr, cllr_min : float or None
        Cross-validated, as for :class:`Calibrator`.
    """

    intercept: float
    weights: dict[str, float]
    lower: float
    upper: float
    cllr: float | None = None
    cllr_min: float | None = None

    def log10_lr(self, detector_llrs: Mapping[str, float]) -> float:
        """The fused log10 LR; a detector absent from ``detector_llrs`` counts as LR 1.

        The intercept may temper the detectors' evidence but not create any:
        the sum stays between the weighted terms for Hd added up and those for
        Hp added up, so that with every detector at LR 1 the fused LR is 1.
        The intercept reflects the make-up of the calibration data (there,
        photos on which no detector found anything were mostly originals),
        not the photo; left free, it read "weak support for Hd" on every
        photo in which no detector found anything, which is calling a photo
        an original for lack of findings.
        """
        terms = [w * detector_llrs.get(name, 0.0) for name, w in self.weights.items()]
        least, most = min(0.0, sum(t for t in terms if t < 0.0)), max(0.0, sum(t for t in terms if t > 0.0))
        return _clip(_clip(self.intercept + sum(terms), least, most), self.lower, self.upper)


@dataclass(frozen=True)
class CalibrationSet:
    """Every calibrator fitted on one body of validation data, with what that data was.

    Attributes
    ----------
    data : dict
        The validation record(s): ``name``, ``source``, ``content_sha256``,
        ``n_hp``, ``n_hd`` and the sets (``conditions``) they hold.
    tool : dict
        Tool and library versions that fitted them.
    calibrators : dict of str to Calibrator
    fusion : Fusion or None
    """

    data: dict[str, Any]
    tool: dict[str, Any]
    calibrators: dict[str, Calibrator]
    fusion: Fusion | None
    format: str = FORMAT
    propositions: dict[str, str] = field(default_factory=lambda: {"hp": HP, "hd": HD})

    def detector_llrs(self, p_values: Mapping[str, float | None],
                      scores: Mapping[str, float | None] | None = None) -> dict[str, float | None]:
        """log10 LR per detector: ``p_values`` maps a detector that ran to its p-value (None when it declined).

        ``scores`` maps it to its score, for calibrators on scores. Detectors
        without a calibrator get None: their output is shown uncalibrated and
        stays out of the fused LR.
        """
        scores = scores or {}
        return {name: (self.calibrators[name].log10_lr(p, scores.get(name)) if name in self.calibrators else None)
                for name, p in p_values.items()}

    def fused(self, llrs: Mapping[str, float | None]) -> float | None:
        """The fused log10 LR of calibrated detectors' log10 LRs, or None without a fusion."""
        if self.fusion is None:
            return None
        return self.fusion.log10_lr({k: v for k, v in llrs.items() if v is not None})

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=1, sort_keys=True) + "\n"


def from_dict(raw: Mapping[str, Any]) -> CalibrationSet:
    """A :class:`CalibrationSet` from its JSON form."""
    if raw.get("format") != FORMAT:
        raise CalibrationError(f"not a calibration file of format {FORMAT} (found {raw.get('format')!r})")
    try:
        fusion = raw.get("fusion")
        return CalibrationSet(
            data=dict(raw["data"]), tool=dict(raw["tool"]),
            calibrators={k: Calibrator(**v) for k, v in raw["calibrators"].items()},
            fusion=Fusion(**fusion) if fusion else None,
            propositions=dict(raw.get("propositions") or {"hp": HP, "hd": HD}),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise CalibrationError(f"calibration file malformed: {exc}") from exc


def load(path: Path) -> CalibrationSet:
    """Read a calibration file; :class:`CalibrationError` with one line when it cannot be used."""
    try:
        raw = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise CalibrationError(f"cannot read calibration file {path}: {exc}") from exc
    if not isinstance(raw, dict):
        raise CalibrationError(f"calibration file {path} is not a JSON object")
    return from_dict(raw)


def load_shipped() -> CalibrationSet | None:
    """The calibrators shipped with the tool, or None when none are."""
    resource = files(__package__).joinpath(SHIPPED)
    if not resource.is_file():
        return None
    return from_dict(json.loads(resource.read_text(encoding="utf-8")))


WEAK_SUPPORT_LR = 2.0
"""The least LR that the verbal scale reads as support (ENFSI's "weak support"); below it and above 1/2,
"no support for either proposition"."""


def supports(log10_lr: float | None) -> int:
    """The side an LR supports as the verbal scale reads it: 1 for Hp, -1 for Hd, 0 for neither (or no LR).

    Every place that says whether a finding supports a side (the report's
    page 1, the photo's line, the validation's operating point) asks this,
    so none can disagree with the words :func:`verbal` prints.
    """
    if log10_lr is None or 10.0 ** abs(log10_lr) < WEAK_SUPPORT_LR:
        return 0
    return 1 if log10_lr > 0 else -1


def verbal(log10_lr: float, hp: str = "Hp (manipulation)", hd: str = "Hd (as the camera produced it)") -> str:
    """ENFSI's verbal equivalent of an LR (Guideline for Evaluative Reporting, 2015, p. 17), for either side.

    ``hp`` and ``hd`` name the propositions (by default the manipulation statement's).
    """
    lr = 10.0 ** abs(log10_lr)
    steps: Sequence[tuple[float, str]] = ((1_000_000.0, "extremely strong"), (10_000.0, "very strong"),
                                          (1_000.0, "strong"), (100.0, "moderately strong"), (10.0, "moderate"),
                                          (WEAK_SUPPORT_LR, "weak"))
    if not supports(log10_lr):
        return "no support for either proposition (the findings are about as probable under both)"
    words = next(w for bound, w in steps if lr >= bound)
    side = hp if log10_lr > 0 else hd
    return f"{words} support for {side}"
