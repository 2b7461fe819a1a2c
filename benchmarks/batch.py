"""Throughput of ``forensics batch`` with 1 and 2 local workers, and peak memory per worker.

Usage: ``python benchmarks/batch.py [--photos 100] [--runs 3] [--workers 1,2] [--detectors a,b] [--format json]``

``--photos`` synthetic authentic 6 MP photos (3000 x 2000, JPEG quality 90,
one seed each, rendered by the lens plugin's ``render_authentic``) are made
once into ``benchmarks/out/batch_6mp/``. Each run is a fresh ``forensics
batch`` process over them into an empty output folder, with ``--workers``
set; runs of the different worker counts are interleaved so that a change of
load on the machine hits them alike. Throughput is photos / minute over the
batch's own elapsed time (``summary.json``: hashing, planning, starting the
workers, analysing, writing; not the interpreter's start-up, printed apart as
the command's wall time). Peak memory per worker is the largest ``VmHWM``
a worker reported and, apart, the largest detector child it forked
(``ru_maxrss``; the detectors run in forked children sharing the worker's
pages, so the two do not add up). Printed: median and range over the runs,
and the speed-up of each worker count over one worker (target: >= 1.8 with
2 workers on a 2-core machine). Also printed, because a busy machine caps
the speed-up whatever the batch does: CPU seconds per photo (the whole
process tree's, from ``RUSAGE_CHILDREN``) and the cores the run actually got
(CPU time / wall time).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from harness import OUT

PHOTOS = OUT / "batch_6mp"
SIZE = (3000, 2000)


def _render(seed: int) -> Path:
    from forensics_plugins.lens_distortion.photo import render_authentic

    path = PHOTOS / f"photo_{seed:03d}.jpg"
    if not path.exists():
        data = render_authentic(seed, size=SIZE, k1=0.08, jpeg_quality=90).jpeg_bytes
        tmp = path.with_suffix(".part")
        tmp.write_bytes(data)
        tmp.replace(path)
    return path


def photos(count: int) -> list[Path]:
    """The first ``count`` benchmark photos, rendering the missing ones on two processes."""
    PHOTOS.mkdir(parents=True, exist_ok=True)
    missing = [s for s in range(count) if not (PHOTOS / f"photo_{s:03d}.jpg").exists()]
    if missing:
        print(f"rendering {len(missing)} photos of {SIZE[0]}x{SIZE[1]} into {PHOTOS} (once)", flush=True)
        with ProcessPoolExecutor(max_workers=2) as pool:
            list(pool.map(_render, missing))
    return [PHOTOS / f"photo_{s:03d}.jpg" for s in range(count)]


def one_run(paths: list[Path], workers: int, detectors: str | None, formats: str) -> dict:
    with tempfile.TemporaryDirectory(prefix="batch-bench-") as tmp:
        out = Path(tmp) / "out"
        args = [sys.executable, "-m", "forensics_core", "batch", *map(str, paths), "--out", str(out),
                "--workers", str(workers), "--format", formats]
        if detectors is not None:
            args += ["--detectors", detectors]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        started = time.perf_counter()
        done = subprocess.run(args, capture_output=True, text=True,
                              env={**os.environ, "FORENSICS_HOME": str(Path(tmp) / "home")})
        wall = time.perf_counter() - started
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        doc = json.loads((out / "summary.json").read_text())
    statuses: dict[str, dict[str, int]] = {}
    for row in doc["photos"]:
        for name, entry in row["detectors"].items():
            counts = statuses.setdefault(name, {})
            counts[entry["status"]] = counts.get(entry["status"], 0) + 1
    run = doc["run"]
    return {
        "returncode": done.returncode,
        "analysed": doc["counts"]["analysed"],
        "failed": doc["counts"]["failed"],
        "elapsed_s": run["elapsed_s"],
        "wall_s": wall,
        "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
        "per_min": doc["counts"]["analysed"] / run["elapsed_s"] * 60,
        "photo_s": statistics.median(r["time_s"] for r in doc["photos"] if r["time_s"] is not None),
        "worker_mb": run["peak_worker_mb"],
        "child_mb": run["peak_detector_child_mb"],
        "statuses": statuses,
    }


def _load() -> str:
    try:
        return Path("/proc/loadavg").read_text().split()[0]
    except OSError:
        return "?"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photos", type=int, default=100)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--workers", default="1,2", help="Comma-separated worker counts.")
    parser.add_argument("--detectors", help="Comma-separated detectors (default: all installed).")
    parser.add_argument("--format", default="json", help="Output formats (json: no report rendering).")
    args = parser.parse_args()
    counts = [int(w) for w in args.workers.split(",")]
    paths = photos(args.photos)
    results: dict[int, list[dict]] = {w: [] for w in counts}
    for run in range(args.runs):
        for workers in counts:
            before = _load()
            result = one_run(paths, workers, args.detectors, args.format)
            results[workers].append(result)
            print(f"run {run + 1}/{args.runs}, {workers} worker(s): {result['per_min']:.1f} photos/min, "
                  f"{result['elapsed_s']:.1f} s, {result['failed']} failed (load average before: {before})",
                  flush=True)
    first = results[counts[0]][0]
    print(f"\nforensics batch on {args.photos} photos of {SIZE[0]}x{SIZE[1]}, --format {args.format}, "
          f"{args.runs} runs per worker count; detectors and statuses of the first run: {first['statuses']}")
    print(f"{'workers':<9}{'photos/min median':>19}{'min':>8}{'max':>8}{'speed-up':>10}{'batch s':>9}"
          f"{'command s':>11}{'photo s':>9}{'CPU s/photo':>13}{'cores used':>12}{'worker MB':>11}{'child MB':>10}")
    base = statistics.median(r["per_min"] for r in results[counts[0]])
    for workers in counts:
        rs = results[workers]
        rate = [r["per_min"] for r in rs]
        print(f"{workers:<9}{statistics.median(rate):>19.1f}{min(rate):>8.1f}{max(rate):>8.1f}"
              f"{statistics.median(rate) / base:>10.2f}{statistics.median(r['elapsed_s'] for r in rs):>9.1f}"
              f"{statistics.median(r['wall_s'] for r in rs):>11.1f}{statistics.median(r['photo_s'] for r in rs):>9.2f}"
              f"{statistics.median(r['cpu_s'] / r['analysed'] for r in rs):>13.2f}"
              f"{statistics.median(r['cpu_s'] / r['wall_s'] for r in rs):>12.2f}"
              f"{max(r['worker_mb'] or 0 for r in rs):>11.0f}{max(r['child_mb'] or 0 for r in rs):>10.0f}")
    print(f"load average now: {_load()} (other processes on the machine take cores from the runs; "
          "'cores used' = CPU time of the whole process tree / command wall time)")


if __name__ == "__main__":
    main()
