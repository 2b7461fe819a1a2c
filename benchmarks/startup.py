"""Start-up time of the commands that analyse nothing: ``--version``, ``--help``, ``plugins``.

Usage: ``python benchmarks/startup.py [--runs 5] [--baseline SOURCE_TREE]``

Each command runs ``--runs`` times as a fresh process (``python -m
forensics_core ...``, so the interpreter's own start is included); printed:
the median, min and max wall time. Target (issue 17): at most 0.3 s each.

``--baseline`` names another source tree of this project (e.g. ``git worktree
add /tmp/base <commit>``); its commands are timed in the same run, with that
tree's ``forensics_core`` and plugins put first on the import path (the
installed entry points name the plugins' modules, which then resolve to that
tree), and printed beside.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness import ROOT, compile_sources, tree_env

COMMANDS = (("--version",), ("--help",), ("plugins",))


def _time(args: tuple[str, ...], env: dict[str, str], cwd: Path) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "forensics_core", *args], env=env, cwd=cwd, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--baseline", type=Path, help="Source tree of the version to compare with.")
    args = parser.parse_args()
    trees = [("this tree", None)] + ([("baseline", args.baseline.resolve())] if args.baseline else [])
    for _, tree in trees:
        print(compile_sources(tree or ROOT))
    with tempfile.TemporaryDirectory() as tmp:
        shim, home = Path(tmp) / "shim", Path(tmp) / "home"
        shim.mkdir()
        results: dict[tuple[str, tuple[str, ...]], list[float]] = {}
        for label, tree in trees:
            env = {**tree_env(tree, shim), "FORENSICS_HOME": str(home)}
            cwd = Path(tmp)
            for command in COMMANDS:
                _time(command, env, cwd)  # warm the file cache
                results[label, command] = [_time(command, env, cwd) for _ in range(args.runs)]
    print(f"{args.runs} runs each, fresh processes; seconds")
    header = f"{'command':<20}" + "".join(f"{label + ' median':>20}{'min':>8}{'max':>8}" for label, _ in trees)
    print(header)
    for command in COMMANDS:
        row = f"{'forensics ' + ' '.join(command):<20}"
        for label, _ in trees:
            v = results[label, command]
            row += f"{statistics.median(v):>20.2f}{min(v):>8.2f}{max(v):>8.2f}"
        print(row)


if __name__ == "__main__":
    main()
