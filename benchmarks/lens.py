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
from pathlib import Path

from harness import OUT, fresh_runs, parse_size, print_stages


_CHILD = r"""
import forensics_core
from forensics_core.evidence import load_evidence
from forensics_plugins.lens_distortion.detector import analyse
from forensics_plugins.lens_distortion.spec import DEFAULT_PARAMS
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
        from forensics_plugins.lens_distortion.photo import render_authentic

        OUT.mkdir(parents=True, exist_ok=True)
        path.write_bytes(render_authentic(7, size=size, k1=0.08, jpeg_quality=90).jpeg_bytes)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", default="4000x3000")
    args = parser.parse_args()
    size = parse_size(args.size)
    target = photo(size)
    runs = fresh_runs(_CHILD, target, args.runs)
    print(f"lens_distortion on {target.name} ({size[0]}x{size[1]}), {args.runs} runs, "
          f"status {runs[0]['status']}, {runs[0]['n_lines']} lines")
    print_stages(runs)


if __name__ == "__main__":
    main()
