"""Fitting calibrators on validation records, with NFI's ``lir``, and measuring them by grouped cross-validation.

Each validation record (``forensics validate``) lists, per photo, its
ground truth and every detector's status, p-value and score; that is all a
calibrator needs, so calibrating never re-analyses a photo.

* Per detector: lir's logistic calibrator (``LogitCalibrator``: logistic
  regression with balanced classes, whose log-odds is the log LR) on
  ``x = -log10 p`` of the photos where the detector ran, or on its score
  for a detector whose spec says it is calibrated on its score
  (``DetectorSpec.calibrated_on``); ELUB bounds from
  ``lir.algorithms.bayeserror.elub`` on its log10 LRs.
* On a score, the four-parameter logistic (:mod:`.model`) replaces the line
  when it fits the calibration data significantly better: a likelihood-ratio
  test of the nested models on the balanced log-likelihood, two more
  parameters, at 5 %, tried with 30 scored photos or more under each
  proposition. A score has floors and ceilings a line cannot follow:
  manipulations a detector cannot see score as originals do, and scenes that
  mimic its trace score as manipulations do. On the shared real corpus
  copy_move's grain peak needed both (cross-validated Cllr 0.74 with the
  line, 0.65 with the four parameters, 0.71 with them one-sided). lir's own
  ``FourParameterLogisticCalibrator`` estimates the floor and the ceiling only
  for infinite scores, so the same model is fitted here with scipy.
* A detector whose spec says its findings cannot support Hd
  (``DetectorSpec.supports_hd``) gets a one-sided calibrator: its lower
  bound is held at 0 (LR 1).
* Fusion: logistic regression (balanced) on the detectors' bounded log10
  LRs, a declining detector entering as 0 (LR 1); the intercept may temper
  their evidence but not create any (:meth:`.model.Fusion.log10_lr`); ELUB
  bounds again. Only detectors that carry information on found photos enter
  it (:func:`fusion_members`): a record made by a generator (its dataset
  has a seed) can teach a detector's calibrator its own kind of forgery, as
  noise's on the realistic cases (AUC 0.61 there, 0.47-0.58 on the real
  sets), but not earn it a weight that real photos would not give.
* Performance: Cllr and Cllr_min (lir.metrics) over every calibration photo,
  declines included as LR 1, each photo's LR computed by calibrators fitted
  on every other scene (leave one scene out, :func:`scene`): copy-move
  variants of one photo, an edit and its original, and one file under two
  names are left out together. Unlike k folds, this depends on no
  assignment of scenes to folds (which moved copy_move's count of authentic
  photos at LR 2 between 4 and 7 of 217 on the real corpus) and fits each
  calibrator on all the data but one scene.

``lir`` (with scikit-learn) is needed only here: ``pip install lir`` or the
``calibrate`` extra.

References
----------
P. Vergeer et al., Science & Justice 56(6), 2016 (ELUB). N. Brümmer, J. du Preez, Computer Speech and Language
20(2-3), 2006 (Cllr). D. Meuwly, D. Ramos, R. Haraksim, A guideline for the validation of likelihood ratio methods
used for forensic evidence evaluation, Forensic Science International 276, 2017, pp. 142-153.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from importlib.metadata import version
from pathlib import Path
from typing import Any

import numpy as np
from scipy.special import expit

from .. import __version__
from .model import Calibrator, CalibrationError, CalibrationSet, Fusion, four_parameter_log10_lr, supports

# Photos under each proposition, with a score, below which the four-parameter
# logistic is not tried: the deviance's chi-squared law is asymptotic, and a
# floor or ceiling fitted on a handful of photos turns the LR into a step.
MIN_FOUR_PARAMETER_PHOTOS = 30
# AUC a detector must reach on at least one found set holding both
# propositions to enter the fusion (issue 42's bar for "carries information
# on real photos"); the others are experimental, shown but not fused.
MIN_FUSION_AUC = 0.6
_LN10 = math.log(10.0)


@dataclass(frozen=True)
class CalibratorInput:
    """What a detector's calibrator reads and whether it may support Hd.

    Attributes
    ----------
    feature : str
        ``"p"`` (``x = -log10 p``) or ``"score"`` (:class:`.model.Calibrator`).
    one_sided : bool
        The detector's findings cannot support Hd (``DetectorSpec.supports_hd``
        false): the calibrator's lower bound is held at 0.
    """

    feature: str = "p"
    one_sided: bool = False


@dataclass(frozen=True)
class Case:
    """One calibration photo: its scene group, ground truth and each detector's p-value and score (None: declined)."""

    name: str
    scene: str
    hp: bool
    p_values: dict[str, float | None]
    set: str = ""
    format: str | None = None
    megapixels: float | None = None
    scores: dict[str, float | None] = field(default_factory=dict)
    record: str = ""

    def llr(self, calibrator: Calibrator) -> float:
        """The calibrator's log10 LR for this photo's finding of its detector."""
        return calibrator.log10_lr(self.p_values.get(calibrator.detector), self.scores.get(calibrator.detector))


def scene(name: str, conditions: dict[str, Any]) -> str:
    """The scene a photo belongs to, so that its variants never straddle cross-validation folds.

    A ``scene`` condition in the suite wins. Otherwise: MICC-F220 names
    (``DSC_1535tamp27``, ``DSC_1535_scale``) give their original's stem;
    edit/original pairs named ``Ixx_...`` give ``Ixx``; anything else is
    its own scene.
    """
    if conditions.get("scene"):
        return str(conditions["scene"])
    stem = name.split("__")[-1]
    prefix = conditions.get("set", "")
    pair = re.match(r"^(?:forged|original)_(I\d+)_", stem)
    if pair:
        return f"{prefix}:{pair.group(1)}"
    micc = re.match(r"^(.*?)(?:tamp\d+|_scale)", stem)
    if micc:
        return f"{prefix}:{micc.group(1)}"
    return f"{prefix}:{stem}"


def _same_bytes_same_scene(rows: Sequence[dict[str, Any]], scenes: list[str]) -> list[str]:
    """``scenes`` with the scenes of photos whose bytes are identical (same SHA-256) joined into one.

    A corpus can hold one file under two names (the IMD pairs hold two
    originals twice, each with its own edit): were the two in different
    scenes, a photo left out would be judged by a calibrator fitted on its
    own bytes.
    """
    from scipy.cluster.hierarchy import DisjointSet

    joined = DisjointSet(scenes)
    first: dict[str, str] = {}
    for row, s in zip(rows, scenes):
        digest = row.get("sha256")
        if digest:
            joined.merge(first.setdefault(digest, s), s)
    # The joined scene is named after its first name in sorted order, whatever order the rows came in.
    return [min(joined.subset(s)) for s in scenes]


def cases_from_rows(rows: Sequence[dict[str, Any]]) -> list[Case]:
    """Calibration cases from a validation record's per-photo rows (photos that failed intake left out)."""
    kept = [c for c in rows if not c.get("error")]
    scenes = _same_bytes_same_scene(kept, [scene(c["name"], c.get("conditions", {})) for c in kept])
    cases = []
    for c, group in zip(kept, scenes):
        p = {name: (d["p_value"] if d["status"] == "ok" else None) for name, d in c["detectors"].items()}
        score = {name: (d.get("score") if d["status"] == "ok" else None) for name, d in c["detectors"].items()}
        conditions = c.get("conditions", {})
        cases.append(Case(name=c["name"], scene=group, hp=bool(c["spliced"]), p_values=p,
                          set=str(conditions.get("set", "")), format=c.get("format"), megapixels=c.get("megapixels"),
                          scores=score))
    return cases


@dataclass(frozen=True)
class Records:
    """What calibration reads from validation records.

    Attributes
    ----------
    cases : list of Case
        Every photo, tagged with its record's name.
    datasets : list of dict
        Each record's dataset description.
    found_aucs : dict of str to float
        Per detector, its best AUC on a set, holding both propositions, of
        a record of found photos (a dataset without a seed: not generated).
    """

    cases: list[Case]
    datasets: list[dict[str, Any]]
    found_aucs: dict[str, float]


def _set_aucs(methods: Sequence[dict[str, Any]]) -> dict[str, float]:
    """Per method of a record, its best per-set AUC (sets holding both propositions)."""
    best: dict[str, float] = {}
    for m in methods:
        for row in m.get("by_condition", []):
            if row.get("key") == "set" and row.get("auc") is not None:
                best[m["name"]] = max(best.get(m["name"], 0.0), float(row["auc"]))
    return best


def read_records(paths: Sequence[Path]) -> Records:
    """Cases, dataset descriptions and found sets' AUCs from validation records; :class:`CalibrationError` when
    unreadable."""
    cases, datasets, aucs = [], [], {}
    for path in paths:
        try:
            record = json.loads(Path(path).read_text(encoding="utf-8"))
            dataset = dict(record["dataset"])
            datasets.append(dataset)
            cases += [replace(c, record=str(dataset["name"])) for c in cases_from_rows(record["cases"])]
            if dataset.get("seed") is None:
                for name, auc in _set_aucs(record.get("methods", [])).items():
                    aucs[name] = max(aucs.get(name, 0.0), auc)
        except OSError as exc:
            raise CalibrationError(f"cannot read validation record {path}: {exc.strerror or exc}") from exc
        except UnicodeDecodeError as exc:
            raise CalibrationError(f"{path}: not a validation record (not UTF-8 text)") from exc
        except ValueError as exc:
            raise CalibrationError(f"{path}: not a validation record (not JSON: {exc})") from exc
        except (KeyError, TypeError) as exc:
            missing = f"no {exc.args[0]!r} field" if isinstance(exc, KeyError) else "fields of the wrong kind"
            raise CalibrationError(f"{path}: not a validation record of `forensics validate` ({missing})") from exc
    return Records(cases, datasets, aucs)


def fusion_members(detectors: Sequence[str], found_aucs: Mapping[str, float]) -> list[str]:
    """The detectors that enter the fusion: those reaching :data:`MIN_FUSION_AUC` on some found set.

    With no found set holding both propositions (``found_aucs`` empty),
    every detector enters: there is nothing to hold them to.
    """
    if not found_aucs:
        return list(detectors)
    return [d for d in detectors if found_aucs.get(d, 0.0) >= MIN_FUSION_AUC]


def _lir():
    try:
        import lir.algorithms.bayeserror as bayeserror
        import lir.metrics as metrics
        from lir.algorithms.logistic_regression import LogitCalibrator
        from lir.data.models import LLRData
    except ImportError as exc:
        raise CalibrationError("fitting calibrators needs NFI's lir: pip install lir") from exc
    return LogitCalibrator, bayeserror, metrics, LLRData


def _logit_line(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(intercept, slope) of log10 LR = intercept + slope x from lir's logistic calibrator."""
    LogitCalibrator, *_ = _lir()
    if len(set(y.tolist())) < 2 or np.ptp(x) == 0:
        return 0.0, 0.0
    cal = LogitCalibrator().fit(x, y)
    return float(cal._logit.intercept_[0]) / _LN10, float(cal._logit.coef_[0, 0]) / _LN10


def _elub(llrs: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    _, bayeserror, _, _ = _lir()
    if len(set(y.tolist())) < 2:
        return 0.0, 0.0
    lower, upper = bayeserror.elub(llrs, y)
    return float(min(lower, 0.0)), float(max(upper, 0.0))


def _balanced_nll(params: np.ndarray, x: np.ndarray, y: np.ndarray) -> float:
    """Negative log-likelihood of the four-parameter logistic, each class weighted to half (lir's balancing)."""
    intercept, slope, floor, ceiling = params
    posterior = floor + (1.0 - floor) / (1.0 + ceiling) * expit(_LN10 * (intercept + slope * x))
    posterior = np.clip(posterior, 1e-12, 1.0 - 1e-12)
    return float(-np.mean(np.log(posterior[y == 1])) - np.mean(np.log1p(-posterior[y == 0])))


def _four_parameters(x: np.ndarray, y: np.ndarray, intercept: float,
                     slope: float) -> tuple[float, float, float, float] | None:
    """(intercept, slope, floor, ceiling) of the four-parameter logistic, or None when it is not significantly
    better than the line (module docstring)."""
    from scipy.optimize import minimize
    from scipy.stats import chi2

    if min(y.sum(), len(y) - y.sum()) < MIN_FOUR_PARAMETER_PHOTOS or np.ptp(x) == 0:
        return None
    line = minimize(_balanced_nll, np.array([intercept, slope, 0.0, 0.0]), args=(x, y), method="L-BFGS-B",
                    bounds=[(None, None), (None, None), (0.0, 0.0), (0.0, 0.0)])
    # The floor stays below P = 1/2 and the ceiling above it, so that each
    # bounds the LR on its own side of 1.
    full = minimize(_balanced_nll, np.array([*line.x[:2], 0.01, 0.01]), args=(x, y), method="L-BFGS-B",
                    bounds=[(None, None), (None, None), (0.0, 0.49), (0.0, 1.0)])
    # The balanced log-likelihood is a mean per class; len(y) / 2 times it is
    # the log-likelihood of the photos with the balancing weights.
    deviance = len(y) * (line.fun - full.fun)
    if not (line.success and full.success) or deviance < chi2.ppf(0.95, df=2):
        return None
    return tuple(float(v) for v in full.x)  # type: ignore[return-value]


def fit_detector(name: str, cases: Sequence[Case], spec: CalibratorInput | None = None) -> Calibrator:
    """A detector's calibrator from the cases where it ran; declines counted, not fitted.

    ``spec`` says the calibrator's feature (``-log10 p`` by default) and
    whether it is one-sided (:class:`CalibratorInput`).
    """
    spec = spec or CalibratorInput()
    kind = spec.feature
    probe = Calibrator(detector=name, intercept=0.0, slope=0.0, lower=0.0, upper=0.0, n_hp=0, n_hd=0, feature=kind)
    values = [(probe.x(c.p_values.get(name), c.scores.get(name)), c) for c in cases if name in c.p_values]
    ran = [(v, c) for v, c in values if v is not None]
    x = np.array([v for v, _ in ran], dtype=float)
    y = np.array([int(c.hp) for _, c in ran])
    intercept, slope = _logit_line(x, y)
    floor = ceiling = 0.0
    if kind == "score":
        intercept, slope, floor, ceiling = _four_parameters(x, y, intercept, slope) or (intercept, slope, 0.0, 0.0)
    llrs = np.array([four_parameter_log10_lr(v, intercept, slope, floor, ceiling) for v in x])
    lower, upper = _elub(llrs, y) if ran else (0.0, 0.0)
    declined = [c for v, c in values if v is None]
    return replace(probe, intercept=intercept, slope=slope, floor=floor, ceiling=ceiling,
                   lower=0.0 if spec.one_sided else lower, upper=upper,
                   n_hp=int(y.sum()), n_hd=int(len(y) - y.sum()),
                   n_declined_hp=sum(c.hp for c in declined), n_declined_hd=sum(not c.hp for c in declined))


def fit_fusion(detectors: Sequence[str], calibrators: dict[str, Calibrator], cases: Sequence[Case]) -> Fusion:
    """Logistic-regression fusion of the calibrated detectors' log10 LRs."""
    from sklearn.linear_model import LogisticRegression

    X = np.array([[c.llr(calibrators[d]) for d in detectors] for c in cases])
    y = np.array([int(c.hp) for c in cases])
    if len(set(y.tolist())) < 2:
        return Fusion(intercept=0.0, weights={d: 0.0 for d in detectors}, lower=0.0, upper=0.0)
    model = LogisticRegression(class_weight="balanced").fit(X, y)
    unbounded = Fusion(intercept=float(model.intercept_[0]) / _LN10,
                       weights={d: float(w) / _LN10 for d, w in zip(detectors, model.coef_[0])},
                       lower=-math.inf, upper=math.inf)
    fused = np.array([unbounded.log10_lr(dict(zip(detectors, row))) for row in X])
    lower, upper = _elub(fused, y)
    return replace(unbounded, lower=lower, upper=upper)


def _fit_all(detectors: Sequence[str], cases: Sequence[Case], features: Mapping[str, CalibratorInput] | None,
             members: Sequence[str] | None = None) -> tuple[dict[str, Calibrator], Fusion]:
    calibrators = {d: fit_detector(d, cases, (features or {}).get(d)) for d in detectors}
    return calibrators, fit_fusion(detectors if members is None else members, calibrators, cases)


def calibrator_inputs(host: Any) -> dict[str, CalibratorInput]:
    """The :class:`CalibratorInput` of each of the host's detectors whose spec departs from the default (calibrated
    on its score, or unable to support Hd)."""
    inputs = {name: CalibratorInput("score" if d.spec.calibrated_on == "score" else "p", not d.spec.supports_hd)
              for name, d in host.detectors.items()}
    return {name: i for name, i in inputs.items() if i != CalibratorInput()}


def cross_validated(detectors: Sequence[str], cases: Sequence[Case],
                    features: Mapping[str, CalibratorInput] | None = None,
                    members: Sequence[str] | None = None) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Per detector and fused, each case's log10 LR from calibrators fitted without its scene.

    ``features`` maps a detector to its :class:`CalibratorInput` (default: on ``-log10 p``, two-sided);
    ``members``, the detectors fused (default: all).
    """
    from sklearn.model_selection import LeaveOneGroupOut

    groups = np.array([c.scene for c in cases])
    per = {d: np.zeros(len(cases)) for d in detectors}
    fused = np.zeros(len(cases))
    for train, test in LeaveOneGroupOut().split(np.zeros(len(cases)), groups=groups):
        calibrators, fusion = _fit_all(detectors, [cases[i] for i in train], features, members)
        for i in test:
            llrs = {d: cases[i].llr(calibrators[d]) for d in detectors}
            for d in detectors:
                per[d][i] = llrs[d]
            fused[i] = fusion.log10_lr(llrs)
    return per, fused


def costs(llrs: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(Cllr, Cllr_min) of log10 LRs with labels ``y`` (1: Hp), by lir."""
    _, _, metrics, LLRData = _lir()
    data = LLRData(features=np.asarray(llrs, dtype=float), labels=np.asarray(y, dtype=int))
    return float(metrics.cllr(data)), float(metrics.cllr_min(data))


def calibrate(paths: Sequence[Path], detectors: Sequence[str] | None = None,
              features: Mapping[str, CalibratorInput] | None = None) -> CalibrationSet:
    """Calibrators, fusion and their cross-validated Cllr from validation records.

    Parameters
    ----------
    paths : sequence of Path
        ``validation.json`` records.
    detectors : sequence of str, optional
        Detectors to calibrate (default: every detector the records hold).
    features : mapping of str to CalibratorInput, optional
        For detectors calibrated on their score or one-sided
        (:func:`calibrator_inputs`); the others on ``-log10 p``, two-sided.

    Returns
    -------
    CalibrationSet
        Its ``data`` names the records, the fused detectors (``fused``) and
        the others with their best found-set AUC (``experimental``), and
        the cross-validated Cllr per record and per set (``costs``).
    """
    read = read_records(paths)
    cases, datasets = read.cases, read.datasets
    if not cases:
        raise CalibrationError("the validation records hold no photo")
    names = sorted({d for c in cases for d in c.p_values}) if detectors is None else list(detectors)
    missing = [d for d in names if not any(d in c.p_values for c in cases)]
    if missing:
        raise CalibrationError(f"no result of {', '.join(missing)} in the validation records")
    y = np.array([int(c.hp) for c in cases])
    if len(set(y.tolist())) < 2:
        raise CalibrationError("the validation records need photos under both propositions")
    members = fusion_members(names, read.found_aucs)
    calibrators, fusion = _fit_all(names, cases, features, members)
    per, fused = cross_validated(names, cases, features, members)
    scored = {d: replace(calibrators[d], **dict(zip(("cllr", "cllr_min"), costs(per[d], y)))) for d in names}
    fusion = replace(fusion, **dict(zip(("cllr", "cllr_min"), costs(fused, y))))

    sizes = [c.megapixels for c in cases if c.megapixels]
    data = {
        "records": [{k: d.get(k) for k in ("name", "source", "content_sha256", "n_cases", "n_spliced", "n_authentic",
                                           "seed")}
                    for d in datasets],
        "n_hp": int(y.sum()), "n_hd": int(len(y) - y.sum()), "n_scenes": len({c.scene for c in cases}),
        "sets": sorted({c.set for c in cases if c.set}),
        "formats": sorted({c.format for c in cases if c.format}),
        "megapixels": [min(sizes), max(sizes)] if sizes else None,
        "cross_validation": f"leave one scene out, {len({c.scene for c in cases})} scenes",
        "fused": members,
        "experimental": {d: round(read.found_aucs.get(d, 0.5), 4) for d in names if d not in members},
        "min_fusion_auc": MIN_FUSION_AUC,
        "costs": _costs_by_part(cases, per, fused, members),
    }
    tool = {"forensics": __version__, "lir": version("lir"), "scikit-learn": version("scikit-learn")}
    return CalibrationSet(data=data, tool=tool, calibrators=scored, fusion=fusion)


def _costs_by_part(cases: Sequence[Case], per: Mapping[str, np.ndarray], fused: np.ndarray,
                   members: Sequence[str]) -> dict[str, dict[str, Any]]:
    """Cross-validated Cllr of the fusion and of each fused detector, per record and per set (both propositions)."""
    y = np.array([int(c.hp) for c in cases])
    parts = {f"record {r}": np.array([c.record == r for c in cases]) for r in sorted({c.record for c in cases})}
    parts |= {f"set {s}": np.array([c.set == s for c in cases]) for s in sorted({c.set for c in cases if c.set})}
    out = {}
    for part, sel in parts.items():
        if 0 < y[sel].sum() < sel.sum():
            out[part] = {"fused": _costs_entry(fused[sel], y[sel]),
                         **{d: _costs_entry(per[d][sel], y[sel]) for d in members}}
    return out


def supports_hp(rows: Sequence[dict[str, Any]],
                features: Mapping[str, CalibratorInput]) -> dict[str, dict[str, bool]]:
    """For detectors calibrated on their score: per photo name, whether its cross-validated LR supports Hp.

    The operating point of a detector that states no test (it decides
    nothing itself): "the calibrated finding supports Hp" as the report's
    verbal scale reads it, an LR of :data:`.model.WEAK_SUPPORT_LR` or more
    ("weak support" or stronger). An LR just above 1 is "no support for
    either proposition" there, and a calibrator that found no evidence in
    the data hovers around 1: counting it as a flag would call a detector
    that says nothing a frequent accuser. Empty when lir is absent or the
    rows hold one proposition only.
    """
    names = sorted(d for d, spec in features.items() if spec.feature == "score")
    cases = cases_from_rows(rows)
    if not names or len({c.hp for c in cases}) < 2:
        return {}
    try:
        _lir()
    except CalibrationError:
        return {}
    present = [d for d in names if any(d in c.p_values for c in cases)]
    per, _ = cross_validated(sorted({d for c in cases for d in c.p_values}), cases, features)
    return {d: {c.name: supports(per[d][i]) > 0 for i, c in enumerate(cases)} for d in present}


def _costs_entry(llrs: np.ndarray, y: np.ndarray) -> dict[str, Any]:
    n_hp, n_hd = int(y.sum()), int(len(y) - y.sum())
    if n_hp == 0 or n_hd == 0:
        return {"n_hp": n_hp, "n_hd": n_hd, "cllr": None, "cllr_min": None, "cllr_cal": None}
    cllr, cllr_min = costs(llrs, y)
    return {"n_hp": n_hp, "n_hd": n_hd, "cllr": round(cllr, 4), "cllr_min": round(cllr_min, 4),
            "cllr_cal": round(cllr - cllr_min, 4)}


def performance(rows: Sequence[dict[str, Any]],
                features: Mapping[str, CalibratorInput] | None = None) -> dict[str, Any]:
    """Cross-validated LR performance of a validation run, per detector and fused, overall and per set.

    Parameters
    ----------
    rows : sequence of dict
        The record's per-photo rows.
    features : mapping of str to CalibratorInput, optional
        As for :func:`calibrate`.

    Returns
    -------
    dict
        ``method``; ``all`` and ``per_set`` (set -> name -> ``n_hp``,
        ``n_hd``, ``cllr``, ``cllr_min``, ``cllr_cal``; only sets holding
        both propositions); ``llrs`` (name ->
        ``hp`` and ``hd``: the cross-validated log10 LRs, for Tippett and ECE
        plots); or ``{"method": ..., "note": why not}`` when they cannot be
        computed (lir absent, one proposition only).
    """
    method = ("log10 LRs of calibrators (lir LogitCalibrator per detector, on a score the four-parameter logistic "
              "where it fits significantly better; logistic fusion; ELUB bounds) fitted "
              "on every other scene (leave one scene out); declines count as LR 1")
    cases = cases_from_rows(rows)
    y = np.array([int(c.hp) for c in cases])
    if len(set(y.tolist())) < 2:
        return {"method": method, "note": "the suite needs photos under both propositions"}
    try:
        _lir()
    except CalibrationError as exc:
        return {"method": method, "note": str(exc)}
    names = sorted({d for c in cases for d in c.p_values})
    per, fused = cross_validated(names, cases, features)
    series = {**per, "verdict": fused}
    sets = np.array([c.set for c in cases])
    out: dict[str, Any] = {"method": method, "all": {n: _costs_entry(v, y) for n, v in series.items()},
                           "per_set": {}, "llrs": {}}
    for name in sorted(set(sets.tolist())):
        sel = sets == name
        if 0 < y[sel].sum() < sel.sum():
            out["per_set"][name] = {n: _costs_entry(v[sel], y[sel]) for n, v in series.items()}
    for n, v in series.items():
        out["llrs"][n] = {"hp": sorted(round(float(x), 4) for x in v[y == 1]),
                          "hd": sorted(round(float(x), 4) for x in v[y == 0])}
    return out
