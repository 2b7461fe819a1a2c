"""What the per-detector benchmarks share: a fresh process per run, peak memory, the stage table.

Each benchmark's child program starts with :data:`CHILD_PRELUDE` (imports and
``hwm_mb()``, the process's peak resident memory from ``VmHWM``) and prints one
JSON object with ``stages`` (seconds by stage), ``peak_mb`` and
``baseline_mb``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
"""The repository's root, whose ``forensics_core`` and ``plugins`` are measured unless ``--baseline`` names another tree."""
OUT = ROOT / "benchmarks" / "out"
"""Where the benchmarks render their photos once, and keep them."""

CHILD_PRELUDE = r"""
import json, re, sys, time
def hwm_mb():
    status = open("/proc/self/status").read()
    return int(re.search(r"VmHWM:\s+(\d+) kB", status).group(1)) / 1024
"""


def compile_sources(tree: Path) -> str:
    """Write the bytecode of ``tree``'s ``forensics_core`` and ``plugins`` (up-to-date files are skipped).

    A wheel is compiled when installed; an editable install or a worktree is
    not, and where Python may not write bytecode (``PYTHONDONTWRITEBYTECODE``)
    every run would compile the project again, about 0.14 s of a 2 s run. Both
    trees of a comparison are compiled alike. Returns the line the benchmarks
    print about it.
    """
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(tree / "forensics_core"), str(plugins_folder(tree))],
                   check=True, stdout=subprocess.DEVNULL)
    return f"bytecode of {tree} compiled, as a wheel install does"


def plugins_folder(tree: Path) -> Path:
    """The bundled plugins' folder of a source tree: ``forensics_plugins/``, or ``plugins/`` in trees before 2026-11-28."""
    return tree / "forensics_plugins" if (tree / "forensics_plugins").is_dir() else tree / "plugins"


def tree_env(tree: Path | None, folder: Path) -> dict[str, str]:
    """This process's environment, with ``tree``'s ``forensics_core``, templates and plugins first on the import path.

    The installed entry points name the plugins' modules
    (``forensics_plugins.*``): a link of that name in ``folder`` to the
    tree's plugins (:func:`plugins_folder`) makes them resolve to that tree.
    ``folder/forensics_core`` is ``tree``'s package laid out as a wheel
    installs it, links to each of its entries (and, in trees before
    2026-11-28, to the top-level ``templates`` that the editable install
    mapped to this repository's), so a baseline renders its reports with its
    own templates. With ``tree`` None, the environment as it is (the
    installed tree).
    """
    env = dict(os.environ)
    if tree is not None:
        link = folder / "forensics_plugins"
        if not link.exists():
            link.symlink_to(plugins_folder(tree))
        package = folder / "forensics_core"
        if not package.exists():
            package.mkdir()
            for entry in (tree / "forensics_core").iterdir():
                if entry.name != "__pycache__":
                    (package / entry.name).symlink_to(entry)
            if not (package / "templates").exists():
                (package / "templates").symlink_to(tree / "templates")
            # The package's own modules are now found here, so their bytecode is written here, once, as for a wheel.
            subprocess.run([sys.executable, "-m", "compileall", "-q", "-l", str(package)], check=True,
                           stdout=subprocess.DEVNULL)
        env["PYTHONPATH"] = os.pathsep.join([str(folder), str(tree)])
    return env


def parse_size(text: str) -> tuple[int, int]:
    """``"4000x3000"`` as ``(4000, 3000)``."""
    w, h = (int(v) for v in text.lower().split("x"))
    return w, h


def fresh_runs(child: str, target: Path, runs: int) -> list[dict[str, Any]]:
    """Run ``child`` on ``target`` ``runs`` times, each in a new interpreter, so no run inherits imports or memory."""
    out = []
    for _ in range(runs):
        done = subprocess.run([sys.executable, "-c", CHILD_PRELUDE + child, str(target)], capture_output=True,
                              text=True, check=True)
        out.append(json.loads(done.stdout))
    return out


def print_stages(runs: list[dict[str, Any]]) -> None:
    """Median, min and max of each stage and of the peak memory over ``runs``."""
    print(f"{'stage':<22}{'median s':>10}{'min s':>10}{'max s':>10}")
    for stage in runs[0]["stages"]:
        values = [r["stages"][stage] for r in runs]
        print(f"{stage:<22}{statistics.median(values):>10.3f}{min(values):>10.3f}{max(values):>10.3f}")
    peaks = [r["peak_mb"] for r in runs]
    print(f"{'peak RSS MB':<22}{statistics.median(peaks):>10.0f}{min(peaks):>10.0f}{max(peaks):>10.0f}")
    print(f"{'baseline RSS MB':<22}{statistics.median(r['baseline_mb'] for r in runs):>10.0f}")


def photo_benchmark(doc: str, name: str, child: str, photo: Callable[[tuple[int, int]], Path]) -> None:
    """The command line of a detector benchmark on one rendered photo: ``--runs`` and ``--size``, then the table."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", default="4000x3000")
    args = parser.parse_args()
    size = parse_size(args.size)
    target = photo(size)
    runs = fresh_runs(child, target, args.runs)
    print(f"{name} on {target.name} ({size[0]}x{size[1]}), {args.runs} runs, score {runs[0]['score']}")
    print_stages(runs)
