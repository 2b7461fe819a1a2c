"""How strong the fused likelihood ratio is, per record and set: issue 42's and issue 38's targets on the records.

Usage: ``python benchmarks/lr_strength.py --fit RECORD [RECORD ...] [--apply RECORD ...]``

The calibrators and the fusion are fitted on the ``--fit`` records as
``forensics calibrate`` fits them, and each of their photos gets its
cross-validated log10 LR (calibrators fitted without its scene, so a photo
never judges itself). Photos of the ``--apply`` records (for example the
innocent-processing record, all authentic, in no fold) get the LR of the
calibrators fitted on every ``--fit`` photo. Per record and per set this
prints, for manipulated photos (Hp), the share with LR >= 2 and >= 100 and
the median; for authentic ones (Hd), the share with LR >= 2 and >= 100, the
largest LR, and per fused detector the share whose own LR is 2 or more;
and the cross-validated Cllr where both propositions are present. Then what
stops the LR short of 100 (:func:`_ceiling`): the ELUB bounds, the LR at
which each fused detector's calibrator levels off, and the authentic photos
whose own LR comes within a factor 10 of its upper bound.

Records are read from the paths given (the shipped ones are in
``forensics_core/validation/``); no photo is read.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from forensics_core.calibration.fit import (_fit_all, calibrator_inputs, costs, cross_validated, fusion_members,
                                            read_records)
from forensics_core.plugins import PluginHost


def _summary(label: str, y: np.ndarray, fused: np.ndarray, per: dict[str, np.ndarray], members: list[str]) -> str:
    lr2, lr100 = np.log10(2.0), 2.0
    out = [f"{label:<56} "]
    hp, hd = fused[y == 1], fused[y == 0]
    if hp.size:
        out.append(f"Hp {hp.size:>4}: >=2 {np.mean(hp >= lr2):6.1%}  >=100 {np.mean(hp >= lr100):6.1%}  "
                   f"median {10 ** np.median(hp):6.2f}   ")
    else:
        out.append(" " * 51)
    if hd.size:
        own = ", ".join(f"{d} {np.mean(per[d][y == 0] >= lr2):.1%}" for d in members)
        out.append(f"Hd {hd.size:>4}: >=2 {np.mean(hd >= lr2):6.1%}  >=100 {np.mean(hd >= lr100):6.1%}  "
                   f"max {10 ** hd.max():7.2f}  (own LR >= 2: {own})")
    if hp.size and hd.size:
        cllr, cllr_min = costs(fused, y)
        out.append(f"  Cllr {cllr:.3f} / min {cllr_min:.3f}")
    return "".join(out)


def _ceiling(cases, calibrators, fusion, per: dict[str, np.ndarray], members: list[str], y: np.ndarray) -> None:
    """Print what stops the LR short of 100: each fused detector's largest LR and the authentic photos that reach
    a tenth of it.

    A four-parameter calibrator's LR levels off at
    ``(c (1 + d) + 1 - c) / ((1 - c) d)`` (floor ``c``, ceiling ``d``:
    :mod:`forensics_core.calibration.model`): the share ``d`` of authentic
    photos its data show scoring as manipulated ones do bounds it, whatever
    the score. Every LR is then clipped to its ELUB bounds.
    """
    print(f"\nwhat stops the LR short of 100: the fused LR's ELUB bounds 10^{fusion.lower:.2f} to 10^{fusion.upper:.2f}")
    for d in members:
        cal = calibrators[d]
        if cal.ceiling > 0.0:
            level = (cal.floor * (1.0 + cal.ceiling) + 1.0 - cal.floor) / ((1.0 - cal.floor) * cal.ceiling)
            shape = (f"levels off at LR {level:.0f} (floor {cal.floor:.3f}, ceiling {cal.ceiling:.4f}: about "
                     f"{cal.ceiling:.1%} of authentic photos score as manipulated ones do)")
        else:
            shape = "a line, unbounded"
        print(f"  {d}: its calibrator {shape}; ELUB bounds 10^{cal.lower:.2f} to 10^{cal.upper:.2f}")
        feature = "score" if cal.feature == "score" else "p"
        near = sorted(((per[d][i], cases[i].name, (cases[i].scores if feature == "score" else cases[i].p_values)
                        .get(d)) for i in np.flatnonzero(y == 0) if per[d][i] >= cal.upper - 1.0), reverse=True)
        for llr, name, value in near:
            shown = "" if value is None else f", {feature} {value:.3g}"
            print(f"    authentic, LR {10 ** llr:.1f} (cross-validated){shown}: {name}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fit", nargs="+", type=Path, required=True)
    ap.add_argument("--apply", nargs="*", type=Path, default=[])
    args = ap.parse_args()

    fit = read_records(args.fit)
    names = sorted({d for c in fit.cases for d in c.p_values})
    features = calibrator_inputs(PluginHost.from_entry_points())
    members = fusion_members(names, fit.found_aucs)
    per, fused = cross_validated(names, fit.cases, features, members)
    print(f"fitted on {', '.join(str(p) for p in args.fit)}; fused: {', '.join(members)}; cross-validated by scene")
    y = np.array([int(c.hp) for c in fit.cases])
    records = np.array([c.record for c in fit.cases])
    sets = np.array([c.set for c in fit.cases])
    print(_summary("all", y, fused, per, members))
    for r in sorted(set(records.tolist())):
        sel = records == r
        print(_summary(f"record {r}", y[sel], fused[sel], {d: v[sel] for d, v in per.items()}, members))
        for s in sorted(set(sets[sel].tolist()) - {""}):
            ss = sel & (sets == s)
            print(_summary(f"  set {s}", y[ss], fused[ss], {d: v[ss] for d, v in per.items()}, members))

    calibrators, fusion = _fit_all(names, fit.cases, features, members)
    _ceiling(fit.cases, calibrators, fusion, per, members, y)

    if args.apply:
        held = read_records(args.apply)
        llrs = {d: np.array([c.llr(calibrators[d]) for c in held.cases]) for d in names}
        hfused = np.array([fusion.log10_lr({d: llrs[d][i] for d in names}) for i in range(len(held.cases))])
        hy = np.array([int(c.hp) for c in held.cases])
        hrec = np.array([c.record for c in held.cases])
        for r in sorted(set(hrec.tolist())):
            sel = hrec == r
            print(_summary(f"applied: record {r}", hy[sel], hfused[sel], {d: v[sel] for d, v in llrs.items()},
                           members))


if __name__ == "__main__":
    main()
