"""End-to-end time and peak memory of ``forensics analyze`` (all detectors, HTML + signed PDF) by photo size.

Usage: ``python benchmarks/end_to_end.py [--runs 5] [--sizes 1,6,12,24 | --photo PATH ...] [--detectors a,b]
[--format json | --compare-formats] [--baseline SOURCE_TREE]``

For each size (megapixels, 4:3) a synthetic authentic JPEG (quality 90) is
rendered once into ``benchmarks/out/``; ``--photo PATH`` (repeatable) times
the given photos instead, e.g. the bundled 3.3 MP camera photo
``tests/data/exif/87_OSError.jpg``. Each run analyses it in a fresh
process that calls the command line in-process (``analyze --format
json,html,pdf``, so intake, every detector, report, signing and manifest),
and reports: the wall time of the whole command; each detector's own time as
findings.json records it (each runs in a forked child); and peak memory: the
command's process (``VmHWM``) and the largest detector child (``ru_maxrss``
of the children). Printed: medians and ranges over the runs, and the
exponent b of time ~ MP^b fitted across sizes (1 = linear).

``--format`` chooses what is written (default ``json,html,pdf``; ``json``
for the first answer without a report). ``--compare-formats`` times instead,
on each photo, ``--format json`` and ``--format json,html,pdf`` (the signed
report) in alternation, run by run, so both meet the machine in the same
state, and prints the two medians and their ratio (target, issue 40: the
signed report at most 1.5 times the JSON-only run). ``--baseline`` names
another source tree of this project, timed in the same run with its
``forensics_core`` and plugins first on the import path, as
``benchmarks/startup.py`` does; with ``--compare-formats`` its runs
alternate with this tree's too. The bytecode of each tree is compiled first,
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
from typing import Any

import numpy as np
from harness import OUT, ROOT, compile_sources, tree_env
from PIL import Image

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

JSON_ONLY = "json"
SIGNED_REPORT = "json,html,pdf"
TARGET_RATIO = 1.5
"""Issue 40: the signed report may take at most this many times the JSON-only run."""


def photo(mp: float) -> Path:
    w = int(round(math.sqrt(mp * 1e6 * 4 / 3) / 8) * 8)
    h = int(round(w * 3 / 4 / 8) * 8)
    path = OUT / f"e2e_{w}x{h}.jpg"
    if not path.exists():
        from forensics_plugins.lens_distortion.photo import render_authentic

        OUT.mkdir(parents=True, exist_ok=True)
        path.write_bytes(render_authentic(11, size=(w, h), k1=0.06, jpeg_quality=90).jpeg_bytes)
    return path


def megapixels(path: Path) -> float:
    """The photo's stored size in megapixels (only the header is read)."""
    with Image.open(path) as img:
        return img.width * img.height / 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--sizes", default="1,6,12,24", help="Megapixels, comma-separated.")
    parser.add_argument("--photo", type=Path, action="append", default=[],
                        help="A photo to time instead of the synthetic sizes; repeatable.")
    parser.add_argument("--detectors", default="", help="Default: all installed.")
    parser.add_argument("--format", help=f"analyze's --format (default {SIGNED_REPORT}).")
    parser.add_argument("--compare-formats", action="store_true",
                        help=f"Time --format {JSON_ONLY} and --format {SIGNED_REPORT} alternately; print the ratio.")
    parser.add_argument("--baseline", type=Path, help="Source tree of the version to compare with.")
    args = parser.parse_args()
    if args.compare_formats and args.format:
        parser.error("--compare-formats times its own two formats; leave out --format")
    for path in args.photo:
        if not path.is_file():
            parser.error(f"--photo {path}: no such file")
    args.format = args.format or SIGNED_REPORT
    if args.photo:
        targets = [(path.resolve(), megapixels(path)) for path in args.photo]
    else:
        targets = [(photo(float(s)), float(s)) for s in args.sizes.split(",")]
    trees = [("this tree", None)] + ([("baseline", args.baseline.resolve())] if args.baseline else [])
    for _, tree in trees:
        print(compile_sources(tree or ROOT))
    with tempfile.TemporaryDirectory() as scratch:
        homes = {}
        for label, tree in trees:
            home = Path(scratch) / label.replace(" ", "_")
            home.mkdir()
            homes[label] = (home, {**tree_env(tree, home), "FORENSICS_HOME": str(home)})
        if args.compare_formats:
            for target, mp in targets:
                _compare_formats(homes, target, mp, args)
        else:
            for label, _ in trees:
                _measure(label, homes[label], targets, args)


def _run(target: Path, detectors: str, formats: str, home: tuple[Path, dict[str, str]]) -> dict[str, Any]:
    """One ``forensics analyze`` in a fresh interpreter: the child's figures and the whole process's wall time."""
    folder, env = home
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", _CHILD, str(target), detectors, formats],
                         capture_output=True, text=True, env=env, cwd=folder)
    if out.returncode != 0:
        # The command reports its own errors on stderr; without them a failed run says only "exit status 1".
        sys.exit(f"analyze --format {formats} of {target} failed under PYTHONPATH={env.get('PYTHONPATH', '')}:\n"
                 + "\n".join(out.stderr.strip().splitlines()[-5:]))
    return {**json.loads(out.stdout.strip().splitlines()[-1]), "wall_s": time.perf_counter() - t0}


def _row(caption: str, values: list[float], digits: int = 2, note: str = "") -> None:
    """One line of a table: median, min and max of ``values``, then ``note``."""
    print(f"{caption:<26}{statistics.median(values):>9.{digits}f}{min(values):>9.{digits}f}"
          f"{max(values):>9.{digits}f}{note}")


def _measure(label: str, home: tuple[Path, dict[str, str]], targets: list[tuple[Path, float]],
             args: argparse.Namespace) -> None:
    medians = []
    for target, mp in targets:
        runs = [_run(target, args.detectors, args.format, home) for _ in range(args.runs)]
        total = [r["total_s"] for r in runs]
        medians.append(statistics.median(total))
        print(f"\n[{label}] {target.name} ({mp:.1f} MP), --format {args.format}, {args.runs} runs in fresh processes")
        print(f"{'':<26}{'median':>9}{'min':>9}{'max':>9}")
        _row("wall, whole process s", [r["wall_s"] for r in runs])
        _row("total (command) s", total)
        for name in runs[0]["detectors"]:
            _row(f"  {name} s", [r["detectors"][name] for r in runs], note=f"   ({runs[0]['status'][name]})")
        _row("  all detectors s", [sum(r["detectors"].values()) for r in runs])
        _row("peak RSS, command MB", [r["main_mb"] for r in runs], 0)
        _row("peak RSS, detector MB", [r["child_mb"] for r in runs], 0)
    if len(targets) > 1 and not args.photo:
        sizes = [mp for _, mp in targets]
        slope = np.polyfit(np.log(sizes), np.log(medians), 1)[0]
        print(f"\ntotal time grows as MP^{slope:.2f} between {sizes[0]:g} and {sizes[-1]:g} MP")


def _compare_formats(homes: dict[str, tuple[Path, dict[str, str]]], target: Path, mp: float,
                     args: argparse.Namespace) -> None:
    """JSON only against the signed report on one photo, every tree and format taking turns within each round."""
    formats = (JSON_ONLY, SIGNED_REPORT)
    runs: dict[tuple[str, str], list[dict[str, Any]]] = {(label, f): [] for label in homes for f in formats}
    for _ in range(args.runs):
        for label, home in homes.items():
            for formats_ in formats:
                runs[label, formats_].append(_run(target, args.detectors, formats_, home))
    for label in homes:
        print(f"\n[{label}] {target.name} ({mp:.1f} MP), {args.runs} runs of each format in fresh processes, "
              f"alternating")
        print(f"{'':<26}{'median':>9}{'min':>9}{'max':>9}")
        medians = {}
        for formats_ in formats:
            print(f"--format {formats_}")
            measured = runs[label, formats_]
            _row("  total (command) s", [r["total_s"] for r in measured])
            _row("  wall, whole process s", [r["wall_s"] for r in measured])
            medians[formats_] = {key: statistics.median(r[key] for r in measured) for key in ("total_s", "wall_s")}
        json_only, signed = medians[JSON_ONLY], medians[SIGNED_REPORT]
        print(f"JSON only {json_only['total_s']:.2f} s, signed report {signed['total_s']:.2f} s (command medians): "
              f"ratio {signed['total_s'] / json_only['total_s']:.2f} (target at most {TARGET_RATIO:g}); "
              f"whole process {json_only['wall_s']:.2f} s, {signed['wall_s']:.2f} s, "
              f"ratio {signed['wall_s'] / json_only['wall_s']:.2f}")


if __name__ == "__main__":
    main()
