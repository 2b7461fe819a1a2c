"""The validation record (``validation.json``): what was measured, on what, with which tool.

Built from the per-photo results of :mod:`.runner`; read back by the report's
"Known error rates" section. :data:`FORMAT` names the layout; bump it when a
field changes meaning.
"""

from __future__ import annotations

import json
from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from importlib.resources import files
from pathlib import Path
from typing import Any

import numpy as np

from ..findings import Status, VerdictLabel
from .metrics import FPR_TARGETS, Rate, auc_bootstrap_ci, rate, roc_auc, roc_curve, suspicion, tpr_at_fpr
from .dependence import PairDependence
from .null_check import VERDICT, VERDICT_RULE, NullCheck
from .runner import CaseResult

FORMAT = "forensics-validation/1"
SHIPPED = "synthetic.json"
"""The record of the built-in synthetic suite shipped in ``forensics_core/validation/`` (``make validate``)."""
SHIPPED_REAL = "real.json"
"""The record of the real-photo corpus shipped beside it (``make validate-real``)."""
SHIPPED_INNOCENT = "innocent_processing.json"
"""The record of the innocent-processing suite shipped beside them (``make validate-innocent-processing``):
the false alarms of every detector and of the verdict on processed authentic photos."""
SHIPPED_REALISTIC = "realistic.json"
"""The record of the realistic suite (``make validate-realistic``): forgeries with true masks made from the real
corpus, on which the calibrators are also fitted and the report's Where map is scored."""

FOUND_IOU = 0.5


@dataclass
class OperatingPoint:
    """The decision actually taken at a fixed rule: its hit and false-alarm rates (exact 95 % intervals)."""

    rule: str
    tpr: Rate
    fpr: Rate


@dataclass
class ConditionMetrics:
    """Figures for the photos carrying one condition tag value.

    Spliced photos with the value are compared with authentic ones with the
    same value when there are any (``authentic_pool`` ``"same"``), else with
    all authentic photos (``"all"``, e.g. for the kind of splice).
    """

    key: str
    value: str
    n_spliced: int
    n_authentic: int
    authentic_pool: str
    auc: float | None
    tpr: Rate
    fpr: Rate
    declined: Rate
    localisation: Localisation | None = None


@dataclass
class Localisation:
    """Pixel-level agreement with the true masks over the spliced photos that have one."""

    n: int
    mcc_mean: float
    iou_mean: float
    found: Rate
    """Share of those photos with IoU >= :data:`FOUND_IOU`."""
    f1_mean: float | None = None
    """Mean pixel F1 (Dice); None in records made before it was kept."""

    @classmethod
    def of(cls, rows: Sequence[_Row]) -> Localisation | None:
        """Over the spliced rows with a true mask; None when there are none."""
        loc = [r for r in rows if r.spliced and r.iou is not None]
        if not loc:
            return None
        return cls(len(loc), float(np.mean([r.mcc for r in loc])), float(np.mean([r.iou for r in loc])),
                   rate(sum(r.iou >= FOUND_IOU for r in loc), len(loc)), float(np.mean([r.f1 for r in loc])))

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> Localisation | None:
        if not d:
            return None
        found = d["found"]
        return cls(d["n"], d["mcc_mean"], d["iou_mean"],
                   Rate(found["k"], found["n"], found["value"], tuple(found["ci"]) if found["ci"] else None),
                   d.get("f1_mean"))


@dataclass
class MethodMetrics:
    """Error rates of one detector, or of the fused verdict."""

    name: str
    version: str
    n_spliced: int
    n_authentic: int
    auc: float | None
    auc_ci: tuple[float, float] | None
    tpr_at_fpr: dict[str, float | None]
    operating_point: OperatingPoint
    declined_spliced: Rate
    declined_authentic: Rate
    errors: int
    localisation: Localisation | None
    by_condition: list[ConditionMetrics]
    roc: list[tuple[float, float]]


@dataclass
class Dataset:
    """Which photos were measured: ``content_sha256`` covers every photo's and mask's bytes and labels."""

    name: str
    source: str
    content_sha256: str
    n_cases: int
    n_spliced: int
    n_authentic: int
    failed_intake: int
    seed: int | None = None
    count: int | None = None


@dataclass
class ValidationRecord:
    format: str
    created: str
    tool: dict[str, str]
    environment: dict[str, Any]
    dataset: Dataset
    fusion: dict[str, Any]
    detector_params: dict[str, dict[str, Any]]
    methods: list[MethodMetrics]
    elapsed_s: float
    cases: list[dict[str, Any]] = field(default_factory=list)
    null_checks: list[NullCheck] = field(default_factory=list)
    dependence: list[PairDependence] = field(default_factory=list)
    likelihood_ratios: dict[str, Any] = field(default_factory=dict)
    """Cross-validated LR performance (:func:`forensics_core.calibration.fit.performance`)."""

    def method(self, name: str) -> MethodMetrics | None:
        return next((m for m in self.methods if m.name == name), None)

    def to_json(self) -> str:
        """The record as indented JSON; a list or mapping of plain values, and each photo's row, on one line."""
        data = asdict(self, dict_factory=_plain)
        cases = data.pop("cases")
        rows = "[\n" + ",\n".join("  " + _dumps(c) for c in cases) + "\n ]" if cases else "[]"
        return f'{_indented(data)[:-2]},\n "cases": {rows}\n}}\n'

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ValidationRecord:
        if data.get("format") != FORMAT:
            raise ValueError(f"not a validation record of format {FORMAT} (found {data.get('format')!r})")

        def r(d):
            return Rate(d["k"], d["n"], d["value"], tuple(d["ci"]) if d["ci"] else None)

        def method(m):
            op = m["operating_point"]
            loc = m.get("localisation")
            return MethodMetrics(
                **{**m,
                   "auc_ci": tuple(m["auc_ci"]) if m["auc_ci"] else None,
                   "operating_point": OperatingPoint(op["rule"], r(op["tpr"]), r(op["fpr"])),
                   "declined_spliced": r(m["declined_spliced"]), "declined_authentic": r(m["declined_authentic"]),
                   "localisation": Localisation.from_dict(loc),
                   "by_condition": [ConditionMetrics(**{**c, "tpr": r(c["tpr"]), "fpr": r(c["fpr"]),
                                                        "declined": r(c["declined"]),
                                                        "localisation": Localisation.from_dict(c.get("localisation"))})
                                    for c in m["by_condition"]],
                   "roc": [tuple(p) for p in m["roc"]]})

        return cls(**{**data, "dataset": Dataset(**data["dataset"]), "methods": [method(m) for m in data["methods"]],
                      "null_checks": [NullCheck.from_dict(c) for c in data.get("null_checks", [])],
                      "dependence": [PairDependence.from_dict(d) for d in data.get("dependence", [])]})


def _dumps(value: Any) -> str:
    return json.dumps(value, ensure_ascii=False, allow_nan=False)


def _indented(value: Any, depth: int = 0) -> str:
    """JSON text indented by one space per level, but with containers of plain values (e.g. ROC points) on one line."""
    nested = [v for v in (value.values() if isinstance(value, dict) else value if isinstance(value, list) else ())
              if isinstance(v, (dict, list))]
    if not nested:
        return _dumps(value)
    pad = " " * (depth + 1)
    if isinstance(value, dict):
        items = [f"{pad}{_dumps(k)}: {_indented(v, depth + 1)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + " " * depth + "}"
    return "[\n" + ",\n".join(pad + _indented(v, depth + 1) for v in value) + "\n" + " " * depth + "]"


def _plain(items: list[tuple[str, Any]]) -> dict[str, Any]:
    return {k: (v.value if isinstance(v, (Status, VerdictLabel)) else v) for k, v in items}


def read_record(path: Path) -> ValidationRecord:
    """Read ``validation.json``; raises OSError or ValueError with a one-line reason."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not JSON ({exc.msg} at line {exc.lineno})") from None
    try:
        return ValidationRecord.from_dict(data)
    except (KeyError, TypeError) as exc:
        raise ValueError(f"{path}: malformed validation record ({exc})") from None


def shipped_record(name: str = SHIPPED) -> ValidationRecord | None:
    """The record ``name`` (:data:`SHIPPED`, :data:`SHIPPED_REAL`, :data:`SHIPPED_INNOCENT` or
    :data:`SHIPPED_REALISTIC`) shipped with this release, or None when absent."""
    resource = files(__package__).joinpath(name)
    if not resource.is_file():
        return None
    return ValidationRecord.from_dict(json.loads(resource.read_text(encoding="utf-8")))


# --------------------------------------------------------------------------- metrics of one method

@dataclass(frozen=True)
class _Row:
    spliced: bool
    conditions: Mapping[str, str]
    suspicion: float
    decided: bool
    flagged: bool
    errored: bool
    mcc: float | None = None
    iou: float | None = None
    f1: float | None = None


def _method_metrics(name: str, version: str, rows: Sequence[_Row], rule: str) -> MethodMetrics:
    pos = np.array([r.suspicion for r in rows if r.spliced])
    neg = np.array([r.suspicion for r in rows if not r.spliced])
    curve = roc_curve(pos, neg)
    spl = [r for r in rows if r.spliced]
    aut = [r for r in rows if not r.spliced]
    localisation = Localisation.of(spl)
    return MethodMetrics(
        name=name, version=version, n_spliced=len(spl), n_authentic=len(aut),
        auc=roc_auc(pos, neg), auc_ci=auc_bootstrap_ci(pos, neg),
        tpr_at_fpr={f"{t:g}": tpr_at_fpr(curve, t) for t in FPR_TARGETS},
        operating_point=OperatingPoint(rule, rate(sum(r.flagged for r in spl), len(spl)),
                                       rate(sum(r.flagged for r in aut), len(aut))),
        declined_spliced=rate(sum(not r.decided for r in spl), len(spl)),
        declined_authentic=rate(sum(not r.decided for r in aut), len(aut)),
        errors=sum(r.errored for r in rows),
        localisation=localisation,
        by_condition=_by_condition(rows),
        roc=curve,
    )


IDENTIFYING_VALUES = 8
"""A condition with more distinct values than this, and than half the photos carrying it, names photos rather
than groups them (a source path, a camera model per photo): it stays in the per-photo rows only."""


def _by_condition(rows: Sequence[_Row]) -> list[ConditionMetrics]:
    values: dict[str, set[str]] = defaultdict(set)
    carrying: dict[str, int] = defaultdict(int)
    for r in rows:
        for k, v in r.conditions.items():
            values[k].add(v)
            carrying[k] += 1
    out = []
    for key in sorted(k for k, v in values.items() if len(v) <= max(IDENTIFYING_VALUES, carrying[k] / 2)):
        for value in sorted(values[key]):
            spl = [r for r in rows if r.spliced and r.conditions.get(key) == value]
            same = [r for r in rows if not r.spliced and r.conditions.get(key) == value]
            aut, pool = (same, "same") if same else ([r for r in rows if not r.spliced], "all")
            if not spl and not same:
                continue
            subset = spl + same
            out.append(ConditionMetrics(
                key=key, value=value, n_spliced=len(spl), n_authentic=len(aut), authentic_pool=pool,
                auc=roc_auc(np.array([r.suspicion for r in spl]), np.array([r.suspicion for r in aut])),
                tpr=rate(sum(r.flagged for r in spl), len(spl)), fpr=rate(sum(r.flagged for r in aut), len(aut)),
                declined=rate(sum(not r.decided for r in subset), len(subset)),
                localisation=Localisation.of(spl),
            ))
    return out


def compute_methods(
    results: Sequence[CaseResult], versions: Mapping[str, str], alpha: float,
    supports_hp: Mapping[str, Mapping[str, bool]] | None = None,
) -> list[MethodMetrics]:
    """Metrics of each detector and of the fused verdict over the photos that were taken in.

    A detector's own operating point is "p-value below ``alpha``" (its test at
    the fusion level, before any correction); for one calibrated on its
    score, "cross-validated LR of 2 or more" where ``supports_hp`` gives it (photo
    name -> bool, :func:`forensics_core.calibration.fit.supports_hp`); for
    any other that states no p-value, "score above 0". The verdict's is
    "inconsistent".
    """
    taken = [r for r in results if r.error is None]
    methods = []
    for name in sorted({n for r in taken for n in r.detectors}):
        with_p = any(r.detectors[name].p_value is not None for r in taken if name in r.detectors)
        by_lr = (supports_hp or {}).get(name) if not with_p else None
        rule = (f"p-value below {alpha:g}" if with_p else
                "calibrated LR of 2 or more, weak support or stronger (cross-validated by scene)" if by_lr is not None
                else "score above 0")

        def row(r: CaseResult) -> _Row:
            d = r.detectors.get(name)
            if d is None:
                return _Row(r.spliced, r.conditions, 0.0, False, False, True)
            decided = d.status is Status.OK
            if with_p:
                flagged = decided and d.p_value is not None and d.p_value < alpha
            elif by_lr is not None:
                flagged = decided and by_lr.get(r.name, False)
            else:
                flagged = decided and (d.score or 0.0) > 0.0
            return _Row(r.spliced, r.conditions, suspicion(d.p_value if with_p else None, d.score, decided),
                        decided, flagged, d.status is Status.ERROR, d.mcc, d.iou, d.f1)

        methods.append(_method_metrics(name, versions.get(name, "unknown"), [row(r) for r in taken], rule))
    verdict_rows = [
        _Row(r.spliced, r.conditions, suspicion(r.verdict_p, None, r.verdict is not VerdictLabel.INCONCLUSIVE),
             r.verdict is not VerdictLabel.INCONCLUSIVE, r.verdict is VerdictLabel.INCONSISTENT, False,
             *((r.where["mcc"], r.where["iou"], r.where["f1"]) if r.where else ()))
        for r in taken
    ]
    methods.append(_method_metrics(VERDICT, "", verdict_rows, VERDICT_RULE))
    return methods


def case_rows(results: Sequence[CaseResult]) -> list[dict[str, Any]]:
    """One compact line per photo for the record, so any figure can be recomputed by hand."""
    return [
        {"name": r.name, "spliced": r.spliced, "sha256": r.sha256, "conditions": r.conditions, "error": r.error,
         "format": r.format, "megapixels": r.megapixels,
         "verdict": r.verdict.value if r.verdict else None, "verdict_p": r.verdict_p,
         "detectors": {n: {"status": d.status.value, "p_value": d.p_value, "score": d.score, "iou": d.iou}
                       for n, d in sorted(r.detectors.items())},
         **({"where": r.where} if r.where is not None else {})}
        for r in results
    ]

