"""``forensics verify`` on hostile bundles: every answer within 20 s, exit 0 or 1, one line per failure.

Usage: ``python benchmarks/verify_hostile.py [--runs N] [--limit S]``

A real bundle is made from the suite's chessboard photo
(``tests/data/calibration/left01.jpg``) with a fresh per-user key in a
temporary ``FORENSICS_HOME``, then copied and tampered with as an attacker or
a careless user would: files replaced by FIFOs or by links to ``/dev/zero``,
a 2 GB sparse PDF, garbage and deep nesting in the manifest, a manifest
re-signed with the examiner's own key that lists 100,000 files, names
outside the folder or in another encoding, and a FIFO or a device given as
the evidence. Each case is verified ``--runs`` times (default 3) as a whole
process; the script prints the median time, the exit code and the first
line of stderr of each, and exits 1 when a case exceeds ``--limit`` seconds
(default 20), exits with another code than 0 or 1, or prints a traceback.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PHOTO = REPO / "tests" / "data" / "calibration" / "left01.jpg"
FORENSICS = [sys.executable, "-m", "forensics_core"]


def _resign(bundle: Path, home: Path, change: Callable[[dict], None]) -> None:
    from forensics_core import signing

    manifest = json.loads((bundle / "manifest.json").read_text())
    change(manifest)
    data = json.dumps(manifest).encode()
    key = signing.load_key(home / f"{signing.DEFAULT_KEY_NAME}.p12", None)
    (bundle / "manifest.json").write_bytes(data)
    (bundle / "manifest.json.p7s").write_bytes(signing.sign_detached(data, key))


def _replace(path: Path, how: str) -> None:
    path.unlink()
    if how == "fifo":
        os.mkfifo(path)
    elif how == "zero":
        path.symlink_to("/dev/zero")
    elif how == "sparse":
        with path.open("wb") as f:
            f.truncate(2 << 30)


def _cases(home: Path, scratch: Path) -> dict[str, tuple[Callable[[Path], None], list[str]]]:
    fifo = scratch / "evidence.fifo"
    os.mkfifo(fifo)
    many = lambda m: m.__setitem__("files", [{"name": f"f{i}.png", "size": 1, "sha256": "0" * 64}
                                            for i in range(100_000)])
    outside = lambda m: m["files"].append({"name": "../../../../etc/passwd", "size": 1, "sha256": "0" * 64})
    odd = lambda m: m["files"].append({"name": "r\u00e9port\udcff\u202e.pdf", "size": 1, "sha256": "0" * 64})
    return {
        "untouched": (lambda b: None, []),
        "manifest is a FIFO": (lambda b: _replace(b / "manifest.json", "fifo"), []),
        "signature is a FIFO": (lambda b: _replace(b / "manifest.json.p7s", "fifo"), []),
        "manifest links to /dev/zero": (lambda b: _replace(b / "manifest.json", "zero"), []),
        "signature links to /dev/zero": (lambda b: _replace(b / "manifest.json.p7s", "zero"), []),
        "PDF links to /dev/zero": (lambda b: _replace(b / "report.pdf", "zero"), []),
        "PDF is a FIFO": (lambda b: _replace(b / "report.pdf", "fifo"), []),
        "PDF is 2 GB sparse": (lambda b: _replace(b / "report.pdf", "sparse"), []),
        "findings is a FIFO": (lambda b: _replace(b / "findings.json", "fifo"), []),
        "manifest nested 100,000 deep": (lambda b: (b / "manifest.json").write_text("[" * 100_000), []),
        "manifest of 1 MB garbage": (lambda b: (b / "manifest.json").write_bytes(os.urandom(1 << 20)), []),
        "signature of 1 MB garbage": (lambda b: (b / "manifest.json.p7s").write_bytes(os.urandom(1 << 20)), []),
        "manifest is a folder": (lambda b: (_replace(b / "manifest.json", "none"), (b / "manifest.json").mkdir()), []),
        "re-signed, 100,000 files listed": (lambda b: _resign(b, home, many), []),
        "re-signed, a file outside": (lambda b: _resign(b, home, outside), []),
        "re-signed, a name not UTF-8 and RLO": (lambda b: _resign(b, home, odd), []),
        "evidence is a FIFO": (lambda b: None, ["--evidence", str(fifo)]),
        "evidence is /dev/zero": (lambda b: None, ["--evidence", "/dev/zero"]),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--limit", type=float, default=20.0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp)
        home = scratch / "home"
        env = {**os.environ, "FORENSICS_HOME": str(home)}
        os.environ["FORENSICS_HOME"] = str(home)
        made = subprocess.run(FORENSICS + ["analyze", str(PHOTO), "--out", str(scratch / "out"),
                                           "--detectors", "metadata,jpeg_grid", "--examiner", "Benchmark"],
                              env=env, capture_output=True, text=True)
        if made.returncode != 0:
            print(made.stderr, file=sys.stderr)
            return 1
        original = scratch / "out" / PHOTO.stem
        failed = False
        print(f"forensics verify on hostile bundles, median of {args.runs} runs (limit {args.limit:g} s)")
        print(f"{'case':36} {'time s':>7} {'exit':>4}  first line of stderr")
        for name, (tamper, extra) in _cases(home, scratch).items():
            bundle = scratch / "case"
            shutil.rmtree(bundle, ignore_errors=True)
            shutil.copytree(original, bundle, symlinks=True)
            tamper(bundle)
            times, codes, line, traceback = [], set(), "", False
            for _ in range(args.runs):
                start = time.perf_counter()
                try:
                    done = subprocess.run(FORENSICS + ["verify", str(bundle), *extra], env=env, capture_output=True,
                                          text=True, timeout=4 * args.limit)
                    codes.add(done.returncode)
                    line = (done.stderr.strip().splitlines() or [""])[0]
                    traceback = traceback or "Traceback" in done.stderr
                except subprocess.TimeoutExpired:
                    codes.add("timeout")
                times.append(time.perf_counter() - start)
            median = statistics.median(times)
            bad = median > args.limit or not codes <= {0, 1} or traceback or (name == "untouched") != (codes == {0})
            failed |= bad
            print(f"{name:36} {median:7.2f} {','.join(map(str, sorted(codes, key=str))):>4}  "
                  f"{line[:110]}{'  <- FAILS' if bad else ''}")
    print("all answered in time with exit 0 or 1" if not failed else "some case failed (marked)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
