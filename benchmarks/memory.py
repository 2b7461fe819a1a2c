"""Peak memory of ``forensics analyze`` on a very large photo, the whole process tree counted once.

Usage: ``python benchmarks/memory.py [--runs 3] [--mp 100] [--format json] [--photo FILE] [--jobs N]
[--baseline TREE] [--per-detector]``

Without ``--photo``, a synthetic authentic JPEG of ``--mp`` megapixels (4:3,
quality 90: a photo of a building from the lens plugin's scene model, scaled
up, with sensor-like noise) is made once into ``benchmarks/out/``. Each run
starts ``forensics analyze`` (all detectors) as a fresh process and samples,
every 50 ms, the proportional set size (PSS, ``/proc/PID/smaps_rollup``) of
the command and of every process below it: detectors run in forked children
that share the parent's pages copy-on-write, so adding their RSS would count
the decoded photo twice, while PSS counts each page once. Printed: the median
and range over the runs of the tree's peak PSS, of the command's own peak RSS
(``VmHWM``), and of the wall time. Targets: at most 2.5 GB at 100 MP (issue
16), 1 GB at 12 MP (issue 17). ``--baseline`` names another source tree of
this project, measured in the same run as ``benchmarks/startup.py`` does.
``--per-detector`` runs each installed detector alone (``--detectors NAME
--jobs 1``) and prints its tree peak and that peak per megapixel of the
photo: the figures the README states.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness import OUT, plugins_folder


def photo(mp: float) -> Path:
    import numpy as np
    from PIL import Image

    w = int(round(math.sqrt(mp * 1e6 * 4 / 3) / 8) * 8)
    h = int(round(w * 3 / 4 / 8) * 8)
    path = OUT / f"memory_{w}x{h}.jpg"
    if path.exists():
        return path
    from forensics_plugins.lens_distortion.photo import render_authentic

    OUT.mkdir(parents=True, exist_ok=True)
    small = render_authentic(11, size=(w // 4, h // 4), k1=0.06, jpeg_quality=95).jpeg_bytes
    with tempfile.NamedTemporaryFile(suffix=".jpg") as tmp:
        tmp.write(small)
        tmp.flush()
        base = Image.open(tmp.name).convert("RGB").resize((w, h), Image.Resampling.BICUBIC)
    rng = np.random.default_rng(7)
    rows = np.asarray(base, dtype=np.int16)
    del base
    for top in range(0, h, 512):
        block = rows[top:top + 512]
        block += rng.normal(0, 2.0, block.shape).round().astype(np.int16)
    Image.fromarray(np.clip(rows, 0, 255).astype(np.uint8)).save(path, quality=90)
    return path


def _tree(root: int) -> list[int]:
    """``root`` and every process below it, from /proc's parent links."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as fh:
                ppid = int(fh.read().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        children.setdefault(ppid, []).append(int(entry))
    found, todo = [], [root]
    while todo:
        pid = todo.pop()
        found.append(pid)
        todo.extend(children.get(pid, []))
    return found


def _pss_kb(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/smaps_rollup") as fh:
            for line in fh:
                if line.startswith("Pss:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def _hwm_kb(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def one_run(target: Path, fmt: str, env: dict[str, str], extra: list[str]) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "forensics_core", "analyze", str(target), "--out", out,
                                 "--format", fmt, *extra], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                # Not this tree's folder: `python -m` would import its forensics_core first.
                                cwd=env["FORENSICS_HOME"])
        peak_tree = peak_main = 0
        while proc.poll() is None:
            peak_tree = max(peak_tree, sum(_pss_kb(p) for p in _tree(proc.pid)))
            peak_main = max(peak_main, _hwm_kb(proc.pid))
            time.sleep(0.05)
        wall = time.perf_counter() - t0
        stderr = proc.stderr.read().decode(errors="replace")
        if proc.returncode != 0:
            raise SystemExit(f"analyze failed ({proc.returncode}): {stderr.strip()[:500]}")
    return {"tree_mb": peak_tree / 1024, "main_mb": peak_main / 1024, "wall_s": wall}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--mp", type=float, default=100.0, help="Megapixels of the synthetic photo.")
    parser.add_argument("--format", default="json", help="analyze's --format (default json).")
    parser.add_argument("--photo", type=Path, help="Measure this photo instead of the synthetic one.")
    parser.add_argument("--baseline", type=Path, help="Source tree of the version to compare with.")
    parser.add_argument("--jobs", type=int,
                        help="analyze's --jobs for this tree (default: analyze's own; a baseline has none).")
    parser.add_argument("--per-detector", action="store_true", help="Each detector alone, its peak per megapixel.")
    args = parser.parse_args()
    target = args.photo or photo(args.mp)
    from PIL import Image

    Image.MAX_IMAGE_PIXELS = None  # our own photo, only its size is read
    with Image.open(target) as im:
        size = f"{im.width}x{im.height} ({im.width * im.height / 1e6:.0f} MP)"
    print(f"{target.name}: {size}, --format {args.format}, {args.runs} runs in fresh processes")
    if args.per_detector:
        per_detector(target, im.width * im.height / 1e6, args)
        return
    print(f"{'':<40}{'median':>9}{'min':>9}{'max':>9}")
    trees = [("", None)] + ([("baseline: ", args.baseline.resolve())] if args.baseline else [])
    for prefix, tree in trees:
        with tempfile.TemporaryDirectory() as home:
            env = {**os.environ, "FORENSICS_HOME": home}
            if tree is not None:
                (Path(home) / "forensics_plugins").symlink_to(plugins_folder(tree))
                env["PYTHONPATH"] = os.pathsep.join([str(tree), home])
            extra = ["--jobs", str(args.jobs)] if args.jobs and tree is None else []
            runs = [one_run(target, args.format, env, extra) for _ in range(args.runs)]
        for key, label in (("tree_mb", "peak PSS, process tree MB"), ("main_mb", "peak RSS, command MB"),
                           ("wall_s", "wall time s")):
            v = [r[key] for r in runs]
            print(f"{prefix + label:<40}{statistics.median(v):>9.0f}{min(v):>9.0f}{max(v):>9.0f}")


def per_detector(target: Path, mp: float, args: argparse.Namespace) -> None:
    from forensics_core.plugins import PluginHost

    names = sorted(PluginHost.from_entry_points().detectors)
    print(f"{'detector alone (--jobs 1)':<28}{'tree MB':>9}{'MB/MP':>8}{'wall s':>8}  (medians)")
    with tempfile.TemporaryDirectory() as home:
        env = {**os.environ, "FORENSICS_HOME": home}
        for name in names:
            runs = [one_run(target, args.format, env, ["--detectors", name, "--jobs", "1"]) for _ in range(args.runs)]
            tree = statistics.median(r["tree_mb"] for r in runs)
            print(f"{name:<28}{tree:>9.0f}{tree / mp:>8.0f}{statistics.median(r['wall_s'] for r in runs):>8.1f}")


if __name__ == "__main__":
    main()
