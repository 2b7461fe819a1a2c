"""End-to-end time and peak memory of ``forensics analyze`` (all detectors, HTML + signed PDF) by photo size.

Usage: ``python benchmarks/end_to_end.py [--runs 5] [--sizes 1,6,12,24] [--detectors a,b] [--format json]
[--baseline SOURCE_TREE]``

For each size (megapixels, 4:3) a synthetic authentic JPEG (quality 90) is
rendered once into ``benchmarks/out/``. Each run analyses it in a fresh
process that calls the command line in-process (``analyze --format
json,html,pdf``, so intake, every detector, report, signing and manifest),
and reports: the wall time of the whole command; each detector's own time as
findings.json records it (each runs in a forked child); and peak memory: the
command's process (``VmHWM``) and the largest detector child (``ru_maxrss``
of the children). Printed: medians and ranges over the runs, and the
exponent b of time ~ MP^b fitted across sizes (1 = linear).

``--format`` chooses what is written (default ``json,html,pdf``; ``json``
for the first answer without a report). ``--baseline`` names another
source tree of this project, timed in the same run with its
``forensics_core`` and plugins first on the import path, as
``benchmarks/startup.py`` does. The bytecode of each tree is compiled first,
as installing a wheel does (:func:`harness.compile_sources`). Targets (issue
17) on a 3 MP photo: at most 2 s with ``--format json``, 4 s with the signed
HTML and PDF.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from harness import OUT, ROOT, compile_sources, tree_env

_CHILD = r"""
import json, os, re, resource, sys, tempfile, time
from pathlib import Path
def hwm_mb():
    return int(re.search(r"VmHWM:\s+(\d+) kB", open("/proc/self/status").read()).group(1)) / 1024
from forensics_core.cli import cli
photo, detectors, formats = sys.argv[1], sys.argv[2], sys.argv[3]
out = Path(tempfile.mkdtemp())
args = ["analyze", photo, "--out", str(out), "--format", formats]
if detectors:
    args += ["--detectors", detectors]
t0 = time.perf_counter()
try:
    cli.main(args, standalone_mode=False)
except SystemExit:
    pass
total = time.perf_counter() - t0
findings = json.loads(next(out.glob("*/findings.json")).read_text())
print(json.dumps({
    "total_s": total,
    "detectors": {d["name"]: d["elapsed_s"] for d in findings["detectors"]},
    "status": {d["name"]: d["status"] for d in findings["detectors"]},
    "main_mb": hwm_mb(),
    "child_mb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024,
}))
"""


def photo(mp: float) -> Path:
    w = int(round(math.sqrt(mp * 1e6 * 4 / 3) / 8) * 8)
    h = int(round(w * 3 / 4 / 8) * 8)
    path = OUT / f"e2e_{w}x{h}.jpg"
    if not path.exists():
        from forensics_plugins.lens_distortion.photo import render_authentic

        OUT.mkdir(parents=True, exist_ok=True)
        path.write_bytes(render_authentic(11, size=(w, h), k1=0.06, jpeg_quality=90).jpeg_bytes)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--sizes", default="1,6,12,24", help="Megapixels, comma-separated.")
    parser.add_argument("--detectors", default="", help="Default: all installed.")
    parser.add_argument("--format", default="json,html,pdf", help="analyze's --format.")
    parser.add_argument("--baseline", type=Path, help="Source tree of the version to compare with.")
    args = parser.parse_args()
    sizes = [float(s) for s in args.sizes.split(",")]
    trees = [("this tree", None)] + ([("baseline", args.baseline.resolve())] if args.baseline else [])
    for _, tree in trees:
        print(compile_sources(tree or ROOT))
    for label, tree in trees:
        _measure(label, tree, sizes, args)


def _measure(label: str, tree: Path | None, sizes: list[float], args: argparse.Namespace) -> None:
    medians = []
    with tempfile.TemporaryDirectory() as home:
        env = {**tree_env(tree, Path(home)), "FORENSICS_HOME": home}
        for mp in sizes:
            target = photo(mp)
            runs = []
            for _ in range(args.runs):
                t0 = time.perf_counter()
                out = subprocess.run([sys.executable, "-c", _CHILD, str(target), args.detectors, args.format],
                                     capture_output=True, text=True, check=True, env=env, cwd=home)
                runs.append({**json.loads(out.stdout.strip().splitlines()[-1]), "wall_s": time.perf_counter() - t0})
            total = [r["total_s"] for r in runs]
            medians.append(statistics.median(total))
            print(f"\n[{label}] {target.name} ({mp:g} MP), --format {args.format}, {args.runs} runs in fresh processes")
            print(f"{'':<26}{'median':>9}{'min':>9}{'max':>9}")
            wall = [r["wall_s"] for r in runs]
            print(f"{'wall, whole process s':<26}{statistics.median(wall):>9.2f}{min(wall):>9.2f}{max(wall):>9.2f}")
            print(f"{'total (command) s':<26}{statistics.median(total):>9.2f}{min(total):>9.2f}{max(total):>9.2f}")
            for name in runs[0]["detectors"]:
                v = [r["detectors"][name] for r in runs]
                print(f"{'  ' + name + ' s':<26}{statistics.median(v):>9.2f}{min(v):>9.2f}{max(v):>9.2f}"
                      f"   ({runs[0]['status'][name]})")
            det_sum = [sum(r["detectors"].values()) for r in runs]
            print(f"{'  all detectors s':<26}{statistics.median(det_sum):>9.2f}{min(det_sum):>9.2f}{max(det_sum):>9.2f}")
            for key, caption in (("main_mb", "peak RSS, command MB"), ("child_mb", "peak RSS, detector MB")):
                v = [r[key] for r in runs]
                print(f"{caption:<26}{statistics.median(v):>9.0f}{min(v):>9.0f}{max(v):>9.0f}")
    if len(sizes) > 1:
        slope = np.polyfit(np.log(sizes), np.log(medians), 1)[0]
        print(f"\ntotal time grows as MP^{slope:.2f} between {sizes[0]:g} and {sizes[-1]:g} MP")


if __name__ == "__main__":
    main()
