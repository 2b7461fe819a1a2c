"""Where the time of one signed report goes: wall and CPU time of each stage, and the least time they allow.

Usage: ``python benchmarks/report_stages.py [--runs 5] [--mp 3 | --photo PATH] [--baseline SOURCE_TREE]``

Each run analyses the photo of :mod:`end_to_end` (``--mp`` megapixels), or
the given photo (e.g. the bundled camera photo
``tests/data/exif/87_OSError.jpg``), with
``analyze --format json,html,pdf`` in a fresh process and times, by wrapping
the functions the pipeline calls: intake (``load_evidence``), the detectors
(``analyze_evidence``, in forked children), the detector sections and the
HTML (``render_html``, sections in forked children), the PDF's layout
(``render_pdf``: the wait for the warm layout process, WeasyPrint, one
thread; :mod:`forensics_core.report.layout_process`) and the two
signatures. For each stage: wall time, and CPU time of the command's
process and of the children it waited for (``os.times``); the layout
process's own CPU (its import and warm-up during the detectors, then the
layout) is read from ``/proc`` and shown as a stage of its own. Printed:
medians over the runs, then two lower bounds for the whole command on
``os.cpu_count()`` cores: all its CPU time spread evenly over the cores,
and the same with the PDF's layout (its wall time) and the signing taken
one after the other on one core, as they must be (the PDF needs every
section; the signature needs the PDF). Issue 17's target for
this command is 4 s on 3 MP.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from end_to_end import photo
from harness import ROOT, compile_sources, tree_env

_CHILD = r"""
import json, os, sys, tempfile, time
from forensics_core.cli import cli
import forensics_core.pipeline as pipeline
import forensics_core.report.bundle as bundle

stages = {}

def timed(module, name, stage):
    inner = getattr(module, name)
    def call(*args, **kwargs):
        t0, c0 = time.perf_counter(), os.times()
        try:
            return inner(*args, **kwargs)
        finally:
            c1 = os.times()
            stages[stage] = {"wall": time.perf_counter() - t0,
                             "cpu": c1.user + c1.system - c0.user - c0.system,
                             "children_cpu": c1.children_user + c1.children_system
                                             - c0.children_user - c0.children_system}
    setattr(module, name, call)

for module, name, stage in ((pipeline, "load_evidence", "intake"), (pipeline, "analyze_evidence", "detectors"),
                            (bundle, "render_html", "sections and HTML"), (bundle, "render_pdf", "PDF layout"),
                            (bundle, "sign_pdf", "PDF signature"), (bundle, "sign_detached", "manifest signature")):
    timed(module, name, stage)
out = tempfile.mkdtemp()
t0, c0 = time.perf_counter(), os.times()
try:
    cli.main(["analyze", sys.argv[1], "--out", out, "--format", "json,html,pdf"], standalone_mode=False)
except SystemExit:
    pass
c1 = os.times()
stages["whole command"] = {"wall": time.perf_counter() - t0, "cpu": c1.user + c1.system - c0.user - c0.system,
                           "children_cpu": c1.children_user + c1.children_system
                                           - c0.children_user - c0.children_system}
try:  # a baseline tree from before the layout process lays out the PDF in the command's own process
    from forensics_core.report.layout_process import started
except ImportError:
    started = None
layout = started() if started is not None else None
if layout is not None:
    fields = open(f"/proc/{layout.pid}/stat").read().rsplit(")", 1)[1].split()
    layout_cpu = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    stages["layout process"] = {"wall": 0.0, "cpu": 0.0, "children_cpu": layout_cpu}
    stages["whole command"]["children_cpu"] += layout_cpu
print(json.dumps(stages))
"""

_SIGNING = ("PDF signature", "manifest signature")


def _runs(target: Path, runs: int, tree: Path | None) -> list[dict[str, dict[str, float]]]:
    out = []
    with tempfile.TemporaryDirectory() as home:
        env = {**tree_env(tree, Path(home)), "FORENSICS_HOME": home}
        for _ in range(runs):
            done = subprocess.run([sys.executable, "-c", _CHILD, str(target)], capture_output=True, text=True,
                                  check=True, env=env, cwd=home)
            out.append(json.loads(done.stdout.strip().splitlines()[-1]))
    return out


def _print(label: str, target: Path, runs: list[dict[str, dict[str, float]]]) -> None:
    cores = os.cpu_count() or 1

    def median(stage: str, key: str) -> float:
        return max(0.0, statistics.median(r[stage][key] for r in runs))

    print(f"\n[{label}] {target.name}, --format json,html,pdf, {len(runs)} runs in fresh processes (medians)")
    print(f"{'stage':<22}{'wall s':>9}{'CPU here s':>12}{'CPU children s':>16}")
    for stage in runs[0]:
        print(f"{stage:<22}{median(stage, 'wall'):>9.2f}{median(stage, 'cpu'):>12.2f}"
              f"{median(stage, 'children_cpu'):>16.2f}")
    whole = [r["whole command"] for r in runs]
    cpu = statistics.median(w["cpu"] + w["children_cpu"] for w in whole)
    serial = statistics.median(r["PDF layout"]["wall"] + sum(r[s]["cpu"] for s in _SIGNING) for r in runs)
    print(f"CPU of the whole command: {cpu:.2f} s. Least wall time on {cores} cores: {cpu / cores:.2f} s with "
          f"all of it in parallel; {serial + (cpu - serial) / cores:.2f} s with the PDF's layout and the signing "
          f"({serial:.2f} s) on one core after the rest.")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--mp", type=float, default=3.0, help="Megapixels of the photo (4:3).")
    parser.add_argument("--photo", type=Path, help="Time this photo instead of a synthetic one.")
    parser.add_argument("--baseline", type=Path, help="Source tree of the version to compare with.")
    args = parser.parse_args()
    target = args.photo.resolve() if args.photo else photo(args.mp)
    trees = [("this tree", None)] + ([("baseline", args.baseline.resolve())] if args.baseline else [])
    for _, tree in trees:
        print(compile_sources(tree or ROOT))
    for label, tree in trees:
        _print(label, target, _runs(target, args.runs, tree))


if __name__ == "__main__":
    main()
