"""Per set and detector: AUC with its interval, detections and false alarms at the verdict's rule and at the
detector's own rule, declines.

Reads one or more ``validation.json`` records (``forensics validate``) and
recomputes the figures from their per-photo rows, so that records of single
sets (run one by one) and one record of many sets (with the ``set``
condition) give comparable tables::

    python benchmarks/validation_table.py out/validation-real/validation.json
    python benchmarks/validation_table.py before/*/validation.json --label before

A detector *convicts* a photo when it drove the verdict: its p-value (or
``min(1, NFA)``), times the number of detectors that stated a test on that
photo (Bonferroni), is below the record's level. A detector that states no
p-value (copy_move) never convicts, however strong its likelihood ratio, so
the columns "at own rule" give what the record itself counted for each
method at its operating point (``methods[].operating_point``: a p-value
below the level, or a calibrated LR of 2 or more cross-validated by scene;
the rules are printed below the table). ``declined`` counts the photos on
which the detector was inconclusive, skipped or failed.

Rates at a rule compare two versions fairly only when both rules hold their
false-alarm rate. The column "TPR at <= K false alarms" compares them at the
same false alarms instead: per method, the threshold on its suspicion that
at most K authentic photos of all the sets pass (``--false-alarms K``,
default 2, i.e. about 1 % of the real corpus's 217), and the manipulated
photos above it.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from forensics_core.validation.metrics import auc_bootstrap_ci, roc_auc, suspicion

VERDICT = "verdict"


def _set_name(record: dict, case: dict) -> str:
    return case.get("conditions", {}).get("set") or record["dataset"]["name"]


def _rows(record: dict) -> dict[tuple[str, str], list[tuple[bool, float, bool, bool]]]:
    """(set, method) -> per photo: (manipulated, suspicion, convicted, declined)."""
    alpha = float(record["fusion"]["alpha"])
    out: dict[tuple[str, str], list[tuple[bool, float, bool, bool]]] = defaultdict(list)
    for case in record["cases"]:
        if case.get("error"):
            continue
        where = _set_name(record, case)
        tests = {n: d["p_value"] for n, d in case["detectors"].items() if d["status"] == "ok" and d["p_value"] is not None}
        m = max(1, len(tests))
        for name, d in case["detectors"].items():
            decided = d["status"] == "ok"
            p = tests.get(name)
            convicted = p is not None and m * p < alpha
            out[(where, name)].append((case["spliced"], suspicion(d["p_value"], d["score"], decided), convicted,
                                       not decided))
        vp = case.get("verdict_p")
        out[(where, VERDICT)].append((case["spliced"], suspicion(vp, None, vp is not None),
                                      case.get("verdict") == "inconsistent", case.get("verdict") == "inconclusive"))
    return out


def matched_threshold(values: list, false_alarms: int) -> float:
    """The suspicion that at most ``false_alarms`` authentic photos of ``values`` exceed (inf when none may)."""
    authentic = sorted((v[1] for v in values if not v[0]), reverse=True)
    return authentic[false_alarms] if false_alarms < len(authentic) else -np.inf


def own_rule(records: list[dict]) -> tuple[dict[tuple[str, str], list[int]], dict[str, str]]:
    """(set, method) -> [flagged manipulated, manipulated, flagged authentic, authentic] at each method's own rule,
    as the records counted them (summed over records), and each method's rule in words."""
    counts: dict[tuple[str, str], list[int]] = defaultdict(lambda: [0, 0, 0, 0])
    rules: dict[str, str] = {}
    for record in records:
        for m in record.get("methods", []):
            rules.setdefault(m["name"], m["operating_point"]["rule"])
            by_set = [c for c in m.get("by_condition", []) if c["key"] == "set"]
            if not by_set:
                op = m["operating_point"]
                by_set = [{"value": record["dataset"]["name"], "tpr": op["tpr"], "fpr": op["fpr"]}]
            for c in by_set:
                for where in (c["value"], "**all**"):
                    entry = counts[(where, m["name"])]
                    entry[0] += c["tpr"]["k"]
                    entry[1] += c["tpr"]["n"]
                    entry[2] += c["fpr"]["k"]
                    entry[3] += c["fpr"]["n"]
    return counts, rules


def table(records: list[dict], label: str, false_alarms: int = 2) -> list[str]:
    rows: dict[tuple[str, str], list] = defaultdict(list)
    for record in records:
        for key, values in _rows(record).items():
            rows[key].extend(values)
    own, rules = own_rule(records)
    lines = [f"| {label} set | method | AUC (95% CI) | TPR at verdict's rule | FPR at verdict's rule "
             f"| TPR at own rule | FPR at own rule | TPR at <= {false_alarms} false alarms | declined (manip. / auth.) |",
             "|---|---|---|---|---|---|---|---|---|"]
    totals: dict[str, list] = defaultdict(list)
    for (where, method), values in sorted(rows.items()):
        totals[method].extend(values)
    thresholds = {method: matched_threshold(values, false_alarms) for method, values in totals.items()}
    for (where, method), values in sorted(rows.items()):
        lines.append(_line(where, method, values, thresholds[method], own.get((where, method))))
    for method, values in sorted(totals.items()):
        lines.append(_line("**all**", method, values, thresholds[method], own.get(("**all**", method))))
    lines.append("")
    lines.extend(f"- own rule of {method}: {rule}" for method, rule in sorted(rules.items()))
    return lines


def _fraction(k: int, n: int) -> str:
    return f"{k}/{n}" if n else "—"


def _line(where: str, method: str, values: list, threshold: float, own: list[int] | None) -> str:
    spl = [v for v in values if v[0]]
    aut = [v for v in values if not v[0]]
    pos = np.array([v[1] for v in spl])
    neg = np.array([v[1] for v in aut])
    auc = roc_auc(pos, neg)
    ci = auc_bootstrap_ci(pos, neg)
    auc_text = "—" if auc is None else f"{auc:.2f}" + (f" ({ci[0]:.2f}–{ci[1]:.2f})" if ci else "")
    tpr = f"{sum(v[2] for v in spl)}/{len(spl)}" if spl else "—"
    fpr = f"{sum(v[2] for v in aut)}/{len(aut)}" if aut else "—"
    matched = f"{sum(v[1] > threshold for v in spl)}/{len(spl)}" if spl else "—"
    own_tpr, own_fpr = (_fraction(own[0], own[1]), _fraction(own[2], own[3])) if own else ("—", "—")
    declined = f"{sum(v[3] for v in spl)}/{len(spl)} / {sum(v[3] for v in aut)}/{len(aut)}"
    return f"| {where} | {method} | {auc_text} | {tpr} | {fpr} | {own_tpr} | {own_fpr} | {matched} | {declined} |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("records", nargs="+", type=Path, help="validation.json files")
    parser.add_argument("--label", default="", help="word put before 'set' in the header (e.g. before, after)")
    parser.add_argument("--false-alarms", type=int, default=2,
                        help="authentic photos, over all sets, a method may pass at the matched threshold")
    args = parser.parse_args()
    records = [json.loads(p.read_text(encoding="utf-8")) for p in args.records]
    print("\n".join(table(records, args.label, args.false_alarms)))


if __name__ == "__main__":
    main()
