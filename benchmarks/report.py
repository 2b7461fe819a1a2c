"""Time the report of a 12 MP photo: HTML + PDF + both signatures + manifest (median of 5).

The analysis is run once beforehand and is not timed (by default with no
detector, so the figure is the report's own cost; pass --detectors to
include sections of installed plugins). A first, untimed run pays for
imports and font loading. Target: <= 3 s.

    python benchmarks/report.py [--runs 5] [--detectors lens_distortion]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

TARGET_S = 3.0


def twelve_megapixel_jpeg(path: Path) -> Path:
    """A 4000 x 3000 JPEG of smooth gradients and sensor-like noise (deterministic)."""
    rng = np.random.default_rng(12)
    y, x = np.mgrid[0:3000, 0:4000].astype(np.float32)
    base = np.stack([x / 4000 * 200, y / 3000 * 180, (x + y) / 7000 * 160], axis=-1) + 30
    pixels = np.clip(base + rng.normal(0, 6, base.shape), 0, 255).astype(np.uint8)
    Image.fromarray(pixels).save(path, "JPEG", quality=92)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--detectors", default="", help="comma-separated detectors to run before timing")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        tmp_path = Path(tmp)
        os.environ["FORENSICS_HOME"] = str(tmp_path / "home")  # a throw-away key, never the user's

        from forensics_core.analysis import Options, analyze_evidence
        from forensics_core.evidence import load_evidence
        from forensics_core.output import write_findings
        from forensics_core.plugins import PluginHost
        from forensics_core.report.bundle import write_bundle
        from forensics_core.report.render import ReportOptions
        from forensics_core.signing import default_key

        photo = twelve_megapixel_jpeg(tmp_path / "twelve.jpg")
        host = PluginHost.from_entry_points()
        evidence = load_evidence(photo)
        detectors = [d for d in args.detectors.split(",") if d]
        findings = analyze_evidence(evidence, host, Options(detectors=detectors, case_id="BENCH", isolation="inline"))
        key = default_key("Benchmark Examiner", "Benchmark Lab")

        def once(i: int) -> tuple[float, int]:
            folder = tmp_path / f"out{i}"
            write_findings(findings, folder)
            started = time.perf_counter()
            write_bundle(findings, evidence, folder, key, host=host, options=ReportOptions(exhibit_id="B-1"))
            return time.perf_counter() - started, (folder / "report.pdf").stat().st_size

        first, _ = once(-1)
        times, sizes = zip(*(once(i) for i in range(args.runs)), strict=True)
        median = statistics.median(times)
        size_mb = photo.stat().st_size / 1e6
        print(f"photo: 4000 x 3000 ({size_mb:.1f} MB JPEG), detectors: {', '.join(detectors) or 'none'}")
        print(f"first run (imports, fonts): {first:.2f} s")
        print(f"report (HTML + PDF + signing + manifest), {args.runs} runs: median {median:.2f} s, "
              f"min {min(times):.2f} s, max {max(times):.2f} s (target <= {TARGET_S:.0f} s: "
              f"{'met' if median <= TARGET_S else 'NOT met'})")
        print(f"report.pdf: {statistics.median(sizes) / 1e6:.2f} MB")


if __name__ == "__main__":
    main()
