"""Time and peak memory of the JPEG grid detector on a 4000 x 3000 photo.

Usage: ``python benchmarks/jpeg_grid.py [--runs 5] [--size 4000x3000]``

A synthetic spliced JPEG (host quality 85, a region from a copy compressed at
quality 80 on the grid (3, 5), the whole saved again at quality 96) is
rendered once into ``benchmarks/out/``, so every stage, region growing
included, has work to do. Each run then analyses it in a fresh process, so
import costs and memory of one run do not leak into the next; numba's
compiled kernels are cached on disk by the first run (its compile time is
printed separately). Printed: the median and range over the runs of each stage
(decode = intake with hashing; the detector's own stages as it records them;
report figures = the section's two PNGs) and of the peak resident memory of
the analysing process (``VmHWM``, which includes the interpreter and the
imported libraries, measured separately as ``baseline``).
Target (issue 5): detector <= 3 s on a 2-core machine.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

from harness import OUT, fresh_runs, parse_size, print_stages


_CHILD = r"""
import forensics_core
from forensics_core.evidence import load_evidence
from forensics_plugins.jpeg_grid.detector import JpegGrid
from forensics_plugins.jpeg_grid.spec import DEFAULT_PARAMS
from forensics_plugins.jpeg_grid.figures import map_png, vote_map_png
base = hwm_mb()
t0 = time.perf_counter()
ev = load_evidence(sys.argv[1])
t1 = time.perf_counter()
result = JpegGrid().analyze(ev, DEFAULT_PARAMS)
t2 = time.perf_counter()
map_png(ev.pixels, result.details)
vote_map_png(result.details)
t3 = time.perf_counter()
stages = {"decode+hash": t1 - t0, **result.details["elapsed_s"], "detector total": t2 - t1, "report figures": t3 - t2}
regions = [r for r in result.details["regions"] if r["meaningful"]]
print(json.dumps({"stages": stages, "peak_mb": hwm_mb(), "baseline_mb": base, "status": result.status.value,
                  "regions": [[r["grid"], r["bbox_px"], r["log10_nfa"]] for r in regions]}))
"""


def photo(size: tuple[int, int]) -> Path:
    path = OUT / f"jpeg_grid_{size[0]}x{size[1]}.jpg"
    if not path.exists():
        from forensics_plugins.jpeg_grid.synth import make_spliced

        OUT.mkdir(parents=True, exist_ok=True)
        case = make_spliced(11, "splice", size=(size[1], size[0]), quality=85, paste_quality=80, final_quality=96,
                            source="coffee", shift=(3, 5))
        path.write_bytes(case.data)
    return path


def _warm(target: Path) -> float:
    """Compile (or load) the numba kernels once; returns the seconds it took."""
    code = ("import time, numpy as np; t = time.perf_counter(); "
            "from forensics_plugins.jpeg_grid.zeros import zero_counts, flat_blocks; "
            "from forensics_plugins.jpeg_grid.regions import components; "
            "from forensics_plugins.jpeg_grid.votes import vote_map; "
            "y = np.zeros((64, 64), np.float32); components(vote_map(zero_counts(y), flat_blocks(y)), np.ones(64, bool)); "
            "print(time.perf_counter() - t)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", default="4000x3000")
    args = parser.parse_args()
    size = parse_size(args.size)
    target = photo(size)
    first = _warm(target)
    runs = fresh_runs(_CHILD, target, args.runs)
    print(f"jpeg_grid on {target.name} ({size[0]}x{size[1]}), {args.runs} runs, status {runs[0]['status']}, "
          f"meaningful regions {runs[0]['regions']}")
    print(f"kernel compile/load before the runs: {first:.2f} s")
    print_stages(runs)


if __name__ == "__main__":
    main()
