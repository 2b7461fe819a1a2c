"""Evaluative reporting: each finding's and the fused likelihood ratio for the stated propositions.

The verdict's label comes from the fusion policy (a triage decision at a
level fixed in advance); the strength of the evidence is stated separately,
as a likelihood ratio from calibrators fitted on validation data
(:mod:`.calibration`; by default the ones shipped with the tool, fitted on the
real-photo corpus). A detector without a calibrator is shown but kept out of
the LR; a detector that declined gives LR 1.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from pathlib import Path

from .calibration import CalibrationSet, load, load_shipped, verbal
from .calibration.model import HD, HP
from .findings import DetectorFinding, EvidenceInfo, LikelihoodRatio, Role, Status, Verdict, VerdictLabel
from .fusion import LR_DECISION_LOG10, LR_POLICY, finding_p

@lru_cache(maxsize=1)
def shipped() -> CalibrationSet | None:
    """The shipped calibrators, read once."""
    return load_shipped()


@lru_cache(maxsize=4)
def calibration_file(path: str | None) -> CalibrationSet | None:
    """The calibrators in ``path`` (read once per process), or the shipped ones for None."""
    return shipped() if path is None else load(Path(path))


def _relevance(calibration: CalibrationSet, info: EvidenceInfo) -> str:
    """One sentence on the calibration data, and whether this photo's format and size lie within theirs."""
    data = calibration.data
    sets = ", ".join(data.get("sets") or [r.get("name", "?") for r in data.get("records", [])])
    mp = info.width * info.height / 1e6
    what = (f"The calibration data are {data.get('n_hp', 0)} manipulated and {data.get('n_hd', 0)} authentic photos "
            f"({sets}).")
    made = [r for r in data.get("records", []) if r.get("seed") is not None]
    if made:
        what += " Of them, " + "; ".join(
            f"{r.get('n_spliced', 0)} manipulated and {r.get('n_authentic', 0)} authentic were made by the tool's "
            f"{r.get('name', '?')} generator (seed {r['seed']}) from authentic photos of the real corpus"
            for r in made) + "."
    formats, span = data.get("formats"), data.get("megapixels")
    if not formats or not span:
        return what + " Their formats and sizes are not recorded, so how far they resemble this photo is not known."
    outside = []
    if info.format not in formats:
        outside.append(f"its format ({info.format}) is not among theirs ({', '.join(formats)})")
    if not span[0] <= mp <= span[1]:
        outside.append(f"its size ({mp:.1f} MP) lies outside theirs ({span[0]:.2g}-{span[1]:.3g} MP)")
    if outside:
        return what + " This photo lies outside them: " + "; ".join(outside) + ", so the LR may not apply to it."
    return (what + f" This photo ({info.format}, {mp:.1f} MP) lies within their formats ({', '.join(formats)}) and "
                   f"sizes ({span[0]:.2g}-{span[1]:.3g} MP).")


def evaluate(findings: Sequence[DetectorFinding], verdict: Verdict, info: EvidenceInfo,
             calibration: CalibrationSet | None = None) -> None:
    """Set each finding's ``log10_lr`` and the verdict's ``log10_lr`` and ``likelihood_ratio``, in place.

    Parameters
    ----------
    findings : sequence of DetectorFinding
    verdict : Verdict
        From the fusion policy; its label is left as it is.
    info : EvidenceInfo
        For the relevance of the calibration data to this photo.
    calibration : CalibrationSet, optional
        Default: the shipped calibrators. Without any, nothing is set.
    """
    calibration = calibration or shipped()
    if calibration is None:
        return
    p_values = {f.name: (finding_p(f) if f.status is Status.OK else None) for f in findings}
    scores = {f.name: (f.score if f.status is Status.OK else None) for f in findings}
    llrs = calibration.detector_llrs(p_values, scores)
    # A detector calibrated on its own data (reference photos) states its LR;
    # its trace, the sensor's noise, is read by no other detector, so it is
    # added to the fusion of the others as independent evidence.
    own = {f.name: f.log10_lr for f in findings if f.status is Status.OK and f.log10_lr is not None}
    llrs.update(own)
    for f in findings:
        f.log10_lr = None if llrs[f.name] is None else round(llrs[f.name], 4)
    fused = calibration.fused({n: v for n, v in llrs.items() if n not in own})
    if fused is not None and own:
        fused += sum(own.values())
    verdict.log10_lr = None if fused is None else round(fused, 4)
    data = calibration.data
    fused_names = set(calibration.fusion.weights) if calibration.fusion else set()
    verdict.likelihood_ratio = LikelihoodRatio(
        hp=calibration.propositions.get("hp", HP),
        hd=calibration.propositions.get("hd", HD),
        log10_lr=verdict.log10_lr,
        verbal=verbal(fused) if fused is not None else "not evaluated: no fusion of calibrated detectors",
        contributed=sorted(n for n, v in llrs.items()
                           if v is not None and abs(v) > 1e-9 and (n in own or n in fused_names)),
        uncalibrated=sorted(f.name for f in findings if llrs[f.name] is None and f.status is Status.OK),
        experimental=sorted(f.name for f in findings if f.status is Status.OK and llrs[f.name] is not None
                            and f.name not in own and f.name not in fused_names),
        calibration={
            "records": [{k: r.get(k) for k in ("name", "content_sha256", "n_cases")} for r in data.get("records", [])],
            "n_hp": data.get("n_hp"), "n_hd": data.get("n_hd"),
            "cross_validation": data.get("cross_validation"),
            "cllr_fused": calibration.fusion.cllr if calibration.fusion else None,
            "cllr_min_fused": calibration.fusion.cllr_min if calibration.fusion else None,
            "elub_fused": [calibration.fusion.lower, calibration.fusion.upper] if calibration.fusion else None,
            "cllr_fused_by_record": {part.removeprefix("record "): entry["fused"]["cllr"]
                                     for part, entry in data.get("costs", {}).items() if part.startswith("record ")},
            "experimental": data.get("experimental", {}),
            "min_fusion_auc": data.get("min_fusion_auc"),
            "tool": dict(calibration.tool),
            **({"own_calibration": {f.name: f.details.get("calibration") for f in findings if f.name in own}}
               if own else {}),
        },
        relevance=_relevance(calibration, info),
    )


def decide_by_lr(verdict: Verdict) -> None:
    """Set the label of a ``likelihood_ratio``-policy verdict from its fused LR, in place (see :mod:`.fusion`)."""
    if verdict.policy != LR_POLICY:
        return
    lr = verdict.likelihood_ratio
    if lr is None or lr.log10_lr is None:
        verdict.label = VerdictLabel.INCONCLUSIVE
        verdict.explanation = "No calibrated likelihood ratio could be computed, so nothing is said either way."
        return
    value = 10.0 ** lr.log10_lr
    if lr.log10_lr >= LR_DECISION_LOG10:
        verdict.label, side = VerdictLabel.INCONSISTENT, "at or above"
    elif lr.log10_lr <= -LR_DECISION_LOG10:
        verdict.label, side = VerdictLabel.CONSISTENT, "at or below"
    else:
        verdict.label, side = VerdictLabel.INCONCLUSIVE, "between"
    bound = f"{10 ** LR_DECISION_LOG10:g}"
    where = {"at or above": bound, "at or below": f"1/{bound}", "between": f"1/{bound} and {bound}"}[side]
    verdict.explanation = (f"The fused likelihood ratio, {value:.3g}, is {side} {where}: {lr.verbal}. "
                           f"Contributing: {', '.join(lr.contributed) or 'no detector'}.")
    verdict.drivers = list(lr.contributed) if verdict.label is not VerdictLabel.INCONCLUSIVE else []
    for c in verdict.contributions:
        if c.detector in verdict.drivers:
            c.role = Role.DROVE
