"""Why dq declines on the manipulated photos of a validation run: what earlier compression is there to find.

Usage: ``python benchmarks/dq_declines.py [OUT/validation-real]`` (default ``out/validation-real``, written by
``make validate-real``; the findings of every photo are in its ``findings/`` folder).

dq (aligned double JPEG, Bianchi & Piva 2012) needs an earlier JPEG save whose
8 x 8 grid is the file's own. Its non-aligned variant needs an earlier save
whose grid the photo still carries at another offset (the photo cropped after
it, or a piece pasted off the grid). jpeg_grid searches all 64 offsets, for
the whole photo (``main_grid``; ``cropped`` when it is not the file's own) and
region by region (``regions`` on another grid). So for each manipulated photo
on which dq gave no finding this prints, grouped by set, dq's status and what
jpeg_grid found: no earlier grid at any offset (nothing for either variant to
read), a whole-photo grid off the origin (non-aligned double JPEG of the whole
photo, i.e. a crop), or regions on another grid (which jpeg_grid reports
itself). The rows of ``validation.json`` say which photos are manipulated.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path


def jpeg_grid_reading(finding: dict) -> str:
    """What jpeg_grid found of an earlier compression, in a few words.

    Parameters
    ----------
    finding : dict
        jpeg_grid's entry of ``findings.json``.

    Returns
    -------
    str
    """
    if finding.get("status") != "ok":
        return f"jpeg_grid {finding.get('status')}"
    details = finding.get("details") or {}
    if details.get("regions"):
        return "regions on another grid"
    if details.get("cropped"):
        return "whole photo on a shifted grid (cropped)"
    return "no earlier grid at any offset"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, nargs="?", default=Path("out/validation-real"))
    args = parser.parse_args()
    record = args.run / "validation.json"
    if not record.exists():
        print(f"no validation run at {args.run} (make validate-real writes one; it needs the real corpus)")
        return
    cases = json.loads(record.read_text())["cases"]
    counts: Counter[tuple[str, str, str, str]] = Counter()
    for case in cases:
        if not case["spliced"] or case["detectors"]["dq"]["status"] == "ok":
            continue
        findings = json.loads((args.run / "findings" / f"{case['name']}.json").read_text())
        by_name = {d["name"]: d for d in findings["detectors"]}
        counts[(case["name"].split("__")[0], case.get("format") or "?", by_name["dq"]["status"],
                jpeg_grid_reading(by_name["jpeg_grid"]))] += 1
    print(f"manipulated photos on which dq gave no finding: {sum(counts.values())}")
    print(f"{'set':<22}{'format':<8}{'dq':<14}{'jpeg_grid':<42}{'photos':>6}")
    for (set_, fmt, status, reading), n in sorted(counts.items()):
        print(f"{set_:<22}{fmt:<8}{status:<14}{reading:<42}{n:>6}")


if __name__ == "__main__":
    main()
