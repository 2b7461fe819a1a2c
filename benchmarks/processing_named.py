"""How often jpeg_grid names processing, and how often it still reports another grid, per kind of a suite.

Usage: ``python benchmarks/processing_named.py SUITE [SUITE ...] [--workers 2] [--out rows.json]
[--module forensics_plugins.jpeg_grid] [--cfa]``

A suite is a folder with ``truth.csv`` (``file``, ``label``, and ``kind`` when
there is one), as ``forensics validate innocent-processing`` or
``lens-splices`` build them (never committed: they are made from the real
corpus, research use only). ``jpeg_grid``'s ``analyse`` runs with its
``DEFAULT_PARAMS`` on each photo; per kind (or label) this prints ``n``, the
photos with a region on another grid that processing does not explain (NFA
below 0.01 / 3, the verdict's share of the 1 % level among three
localising detectors), the photos whose finding names processing
(``details["processing"]``), and the photos where either holds: where the
first compression's grid survives, the share named is the last two's ratio
(issue 38: lens correction at quality 98 named on at least 80 % of those).
``--module`` runs another copy of the plugin (on ``PYTHONPATH``), to set
figures before and after a change side by side. ``--cfa`` also runs the
``cfa`` detector on each photo twice, alone and with ``jpeg_grid``'s finding
as its ``prior`` (the lens correction it names moves the mosaic too), and
prints per kind the photos it calls (NFA below the same level) each way and
those where it names the processing.
"""

from __future__ import annotations

import argparse
import csv
import importlib
import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

CALLED_NFA = 0.01 / 3


def _cfa(evidence: object, result: object) -> dict[str, object]:
    """cfa alone and told of jpeg_grid's ``result``: their NFAs, and the processing it then names."""
    from forensics_core import DetectorFinding
    from forensics_plugins.cfa.detector import ColourFilterArray
    from forensics_plugins.cfa.spec import DEFAULT_PARAMS, JPEG_GRID

    finding = DetectorFinding(name=JPEG_GRID, version="", plugin="", status=result.status, summary="", score=None,
                              p_value=None, nfa=result.nfa, details=result.details, parameters={}, elapsed_s=0.0)
    alone = ColourFilterArray().analyze(evidence, DEFAULT_PARAMS, prior={})
    told = ColourFilterArray().analyze(evidence, DEFAULT_PARAMS, prior={JPEG_GRID: finding})
    return {"cfa_alone_nfa": alone.nfa, "cfa_nfa": told.nfa,
            "cfa_processing": (told.details.get("processing") or {}).get("kind")}


def _run(job: tuple[str, str, bool]) -> dict[str, object]:
    module, path, with_cfa = job
    from forensics_core.evidence import load_evidence

    from forensics_core import Detector

    detector = importlib.import_module(f"{module}.detector")
    spec = importlib.import_module(f"{module}.spec")
    # Trees before plugin API 2 have a module function; later ones the Detector's method.
    run = getattr(detector, "analyse", None) or next(
        v for v in vars(detector).values() if isinstance(v, type) and issubclass(v, Detector) and v is not Detector)().analyze
    evidence = load_evidence(path)
    result = run(evidence, spec.DEFAULT_PARAMS)
    processing = result.details.get("processing") or {}
    return {"status": result.status.value, "nfa": result.nfa, "processing": processing.get("kind"),
            **(_cfa(evidence, result) if with_cfa else {})}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("suites", type=Path, nargs="+")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--module", default="forensics_plugins.jpeg_grid")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--cfa", action="store_true", help="Also run cfa alone and told of jpeg_grid's finding.")
    args = parser.parse_args()
    rows = []
    for suite in args.suites:
        truth = suite / "truth.csv"
        if not truth.is_file():
            raise SystemExit(f"{suite}: no truth.csv (build the suite with forensics validate first)")
        with truth.open(newline="", encoding="utf-8") as f:
            rows += [{**r, "path": str(suite / r["file"])} for r in csv.DictReader(f)]
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(_run, [(args.module, r["path"], args.cfa) for r in rows]))
    by_kind: dict[str, list[dict[str, object]]] = {}
    for row, out in zip(rows, results):
        row.update(out)
        row["called"] = out["nfa"] is not None and out["nfa"] < CALLED_NFA
        by_kind.setdefault(row.get("kind") or row["label"], []).append(row)
    print(f"{args.module}: another grid = region unexplained by processing, NFA < {CALLED_NFA:.4f}")
    print(f"{'kind':28s} {'n':>4s} {'another grid':>13s} {'named':>6s} {'either':>7s}  named / either")
    for kind, group in sorted(by_kind.items()):
        called = sum(bool(r["called"]) for r in group)
        named = sum(r["processing"] is not None for r in group)
        either = sum(bool(r["called"]) or r["processing"] is not None for r in group)
        share = f"{100 * named / either:.0f} %" if either else "-"
        print(f"{kind:28s} {len(group):4d} {called:13d} {named:6d} {either:7d}  {share}")
    if args.cfa:
        def called(v: object) -> bool:
            return v is not None and v < CALLED_NFA

        print(f"\ncfa: called = a region of another phase, NFA < {CALLED_NFA:.4f}; alone, and told of jpeg_grid's "
              "finding")
        print(f"{'kind':28s} {'n':>4s} {'alone':>6s} {'told':>6s} {'named':>6s}")
        for kind, group in sorted(by_kind.items()):
            print(f"{kind:28s} {len(group):4d} {sum(called(r['cfa_alone_nfa']) for r in group):6d} "
                  f"{sum(called(r['cfa_nfa']) for r in group):6d} "
                  f"{sum(r['cfa_processing'] is not None for r in group):6d}")
    if args.out:
        args.out.write_text(json.dumps(rows, indent=1), encoding="utf-8")


if __name__ == "__main__":
    main()
