"""Time and peak memory of the prnu detector on real camera photos: the fingerprint from ten references, and the
test of one photo with the fingerprint cached.

Usage: ``python benchmarks/prnu.py --dresden DIR [--runs 5] [--unit Nikon_D70_1]``

``DIR`` holds the test data of ``polimi-ispl/prnu-python`` (``ff-jpg/``,
flat-field photos; ``nat-jpg/``, natural photos), read where it lies and
never copied. Each run is a fresh process: it takes in the unit's ten
flat-field photos as ``--reference`` material does, estimates the
fingerprint with an empty cache ("fingerprint"), then tests one natural
photo of the unit as ``forensics analyze`` runs the detector, the
fingerprint now cached ("test"). Targets (issue 43): fingerprint from 10
references of 6 MP under 60 s; the test of one photo under 5 s.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

from harness import fresh_runs, print_stages

_CHILD = r"""
import os, tempfile
os.environ["FORENSICS_CACHE"] = tempfile.mkdtemp()
from forensics_core import load_evidence, load_references
from forensics_plugins.prnu.detector import Prnu
from forensics_plugins.prnu.spec import DEFAULT_PARAMS
refs_dir, photo = sys.argv[1].split("|")
base = hwm_mb()
t0 = time.perf_counter()
refs = load_references(refs_dir, max_pixels=10**9)
t1 = time.perf_counter()
first = Prnu().analyze(load_evidence(photo), DEFAULT_PARAMS, refs)
t2 = time.perf_counter()
evidence = load_evidence(photo)
t3 = time.perf_counter()
second = Prnu().analyze(evidence, DEFAULT_PARAMS, refs)
t4 = time.perf_counter()
assert second.details["reference"]["cached"]
print(json.dumps({"stages": {"references intake": t1 - t0, "fingerprint+test": t2 - t1,
                             "photo intake": t3 - t2, "test (cached)": t4 - t3},
                  "peak_mb": hwm_mb(), "baseline_mb": base, "pce": second.details["pce"]}))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dresden", type=Path, required=True)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--unit", default="Nikon_D70_1")
    args = parser.parse_args()
    flat = sorted((args.dresden / "ff-jpg").glob(f"{args.unit}_*.JPG"))[:10]
    natural = sorted((args.dresden / "nat-jpg").glob(f"{args.unit}_*.JPG"))
    if not flat or not natural:
        print(f"{args.dresden}: no ff-jpg/{args.unit}_*.JPG or nat-jpg/{args.unit}_*.JPG; fetch "
              "polimi-ispl/prnu-python's test/data", file=sys.stderr)
        raise SystemExit(1)
    refs = Path(tempfile.mkdtemp())
    try:
        for f in flat:
            (refs / f.name).symlink_to(f.resolve())
        runs = fresh_runs(_CHILD, f"{refs}|{natural[0]}", args.runs)
    finally:
        shutil.rmtree(refs)
    print(f"{len(flat)} references of {args.unit}, photo {natural[0].name}, {args.runs} fresh processes")
    print_stages(runs)
    fingerprint = sorted(r["stages"]["fingerprint+test"] - r["stages"]["test (cached)"] for r in runs)
    print(f"fingerprint alone (fingerprint+test - test), median: {fingerprint[len(fingerprint) // 2]:.2f} s")


if __name__ == "__main__":
    main()
