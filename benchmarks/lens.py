"""Time and peak memory of the lens distortion detector on a 4000 x 3000 photo.

Usage: ``python benchmarks/lens.py [--runs 5] [--size 4000x3000]``

A synthetic authentic JPEG (quality 90) is rendered once into
``benchmarks/out/``; each run then analyses it in a fresh process, so import
costs and memory of one run do not leak into the next. Printed: the median
and range over the runs of each stage (decode = intake with hashing; the
detector's own stages as it records them) and of the peak resident memory of
the analysing process (``VmHWM``, which includes the interpreter and the
imported libraries, measured separately as ``baseline``).
Targets (issue 3): detector <= 3 s and <= 1.5 GB on a 2-core machine.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

OUT = Path(__file__).resolve().parent / "out"

_CHILD = r"""
import json, re, sys, time
def hwm_mb():
    status = open("/proc/self/status").read()
    return int(re.search(r"VmHWM:\s+(\d+) kB", status).group(1)) / 1024
import forensics_core
from forensics_core.evidence import load_evidence
from forensics_plugins.lens_distortion.detector import DEFAULT_PARAMS, analyse
base = hwm_mb()
t0 = time.perf_counter()
ev = load_evidence(sys.argv[1])
luma = ev.luma
t1 = time.perf_counter()
result = analyse(luma, DEFAULT_PARAMS)
t2 = time.perf_counter()
stages = {"decode+hash+luma": t1 - t0, **result.details["elapsed_s"], "detector total": t2 - t1}
print(json.dumps({"stages": stages, "peak_mb": hwm_mb(), "baseline_mb": base, "status": result.status.value,
                  "n_lines": len(result.details["lines"])}))
"""


def photo(size: tuple[int, int]) -> Path:
    path = OUT / f"lens_{size[0]}x{size[1]}.jpg"
    if not path.exists():
        from forensics_plugins.lens_distortion.synth import render_authentic

        OUT.mkdir(parents=True, exist_ok=True)
        path.write_bytes(render_authentic(7, size=size, k1=0.08, jpeg_quality=90).jpeg_bytes)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", default="4000x3000")
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    target = photo(size)
    runs = []
    for _ in range(args.runs):
        out = subprocess.run([sys.executable, "-c", _CHILD, str(target)], capture_output=True, text=True, check=True)
        runs.append(json.loads(out.stdout))
    print(f"lens_distortion on {target.name} ({size[0]}x{size[1]}), {args.runs} runs, "
          f"status {runs[0]['status']}, {runs[0]['n_lines']} lines")
    print(f"{'stage':<22}{'median s':>10}{'min s':>10}{'max s':>10}")
    for stage in runs[0]["stages"]:
        values = [r["stages"][stage] for r in runs]
        print(f"{stage:<22}{statistics.median(values):>10.3f}{min(values):>10.3f}{max(values):>10.3f}")
    peaks = [r["peak_mb"] for r in runs]
    print(f"{'peak RSS MB':<22}{statistics.median(peaks):>10.0f}{min(peaks):>10.0f}{max(peaks):>10.0f}")
    print(f"{'baseline RSS MB':<22}{statistics.median(r['baseline_mb'] for r in runs):>10.0f}")


if __name__ == "__main__":
    main()
