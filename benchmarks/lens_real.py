"""Calibration of the lens distortion detector's null on the shared real authentic photos.

Usage: ``python benchmarks/lens_real.py [--corpus /work/shared/data/real] [--workers 2]``

Runs the detector (default parameters) on every authentic photo of
``authentic_buildings/*`` and ``authentic_charts/digicam_corpus`` and prints,
per set and overall:

* how often the detector runs (status ok) and how many lines it finds;
* the per-line departure ``z`` of the informative lines: the fraction within
  +-1.96 (target 93-97 %: the error model of
  ``forensics_plugins.lens_distortion.consistency`` makes it N(0, 1) under
  the null) and beyond +-3;
* the image-level p-values: the largest excess of their empirical CDF over
  the diagonal (<= 0 means the test is valid or conservative on this corpus)
  and the count below 0.01 / 3 (called a splice by the team's rule);
* one camera, one k1 (issue 12, item 4): photos grouped by EXIF camera, focal
  length and pixel size (from each set's ``exif.csv``); for every group with
  two or more photos where the detector ran, the global k1 of each, their
  inverse-variance mean and Cochran's homogeneity test ``Q = sum((k1_i -
  mean)^2 / se_i^2)`` against chi-square with ``n - 1`` degrees of freedom
  (a small p-value: the stated uncertainties do not cover the spread between
  photos of one lens at one setting).

With OpenCV installed (it is not a dependency), the number of LSD segments at
least as long as the detector's minimum is printed beside the detector's line
count. Without the corpus it prints "corpus absent" and exits 0. The photos
are only read, never copied.
"""

from __future__ import annotations

import argparse
import csv
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

SETS = (
    "authentic_buildings/dresden_prnu-python",
    "authentic_buildings/metadata-extractor-images",
    "authentic_buildings/metadata-extractor-images_rotated",
    "authentic_charts/digicam_corpus",
)
CONVICTION_P = 0.01 / 3


def photos(corpus: Path) -> list[tuple[str, Path, str]]:
    """(set, path, group) of every authentic photo; group = camera, focal length and pixel size from exif.csv."""
    out = []
    for name in SETS:
        truth = corpus / name / "truth.csv"
        if not truth.exists():
            continue
        groups = {}
        exif = corpus / name / "exif.csv"
        if exif.exists():
            with exif.open(newline="") as f:
                for row in csv.DictReader(f):
                    size = "x".join(sorted((row["width"], row["height"]), key=int, reverse=True))
                    groups[row["file"]] = f"{row['make']} {row['model']}, {row['focal_length_mm']} mm, {size}"
        with truth.open(newline="") as f:
            out += [(name, corpus / name / row["file"], groups.get(row["file"], ""))
                    for row in csv.DictReader(f) if row["label"] == "authentic"]
    return out


def _lsd_count(luma: np.ndarray, min_length_px: float) -> int | None:
    try:
        import cv2
    except ImportError:
        return None
    segments = cv2.createLineSegmentDetector().detect((255 * luma).astype(np.uint8))[0]
    if segments is None:
        return 0
    s = segments.reshape(-1, 4)
    return int(np.sum(np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]) >= min_length_px))


def run_one(item: tuple[str, Path, str]) -> dict:
    from forensics_core.evidence import load_evidence
    from forensics_plugins.lens_distortion.detector import analyse
    from forensics_plugins.lens_distortion.spec import DEFAULT_PARAMS

    name, path, group = item
    luma = load_evidence(path).luma
    result = analyse(luma, DEFAULT_PARAMS)
    lines = result.details["lines"]
    model = result.details.get("global_model") or {}
    z = [ln["z"] for ln in lines if ln["informative"] and ln["z"] is not None]
    return {
        "set": name, "file": path.name, "status": result.status.value, "p": result.p_value, "z": z,
        "n_lines": len(lines), "lsd": _lsd_count(luma, DEFAULT_PARAMS["min_length_fraction"] * min(luma.shape)),
        "group": group, "k1": model.get("k1"), "k1_stderr": model.get("k1_stderr"),
    }


def _homogeneity(rows: list[dict]) -> None:
    """Cochran's Q over the global k1 of the photos of each camera, focal length and size."""
    from scipy import stats

    groups: dict[str, list[dict]] = {}
    for r in rows:
        if r["group"] and r["status"] == "ok" and r["k1"] is not None and (r["k1_stderr"] or 0) > 0:
            groups.setdefault(r["group"], []).append(r)
    print("one camera, one k1 (Cochran's Q; groups with 2 or more photos where the detector ran):")
    tested = 0
    for group, members in sorted(groups.items()):
        if len(members) < 2:
            continue
        tested += 1
        k = np.array([m["k1"] for m in members])
        se = np.array([m["k1_stderr"] for m in members])
        w = 1.0 / se**2
        mean = float(np.sum(w * k) / np.sum(w))
        q = float(np.sum(w * (k - mean) ** 2))
        p = float(stats.chi2.sf(q, len(k) - 1))
        print(f"  {group:52s} n {len(k):2d}  k1 {mean:+.4f} +- {np.sqrt(1 / np.sum(w)):.4f}  "
              f"range {k.min():+.4f}..{k.max():+.4f}  median se {np.median(se):.4f}  Q {q:7.2f}  p {p:.3g}")
    if not tested:
        print("  no group holds two photos where the detector ran")


def _report(label: str, rows: list[dict]) -> None:
    z = np.abs(np.concatenate([r["z"] for r in rows])) if rows else np.zeros(0)
    p = np.sort([r["p"] for r in rows if r["status"] == "ok"])
    ok = len(p)
    excess = float(np.max(np.arange(1, ok + 1) / ok - p)) if ok else float("nan")
    lsd = [r["lsd"] for r in rows if r["lsd"] is not None]
    print(f"{label:55s} ok {ok:3d}/{len(rows):3d} ({ok / max(len(rows), 1):4.0%})  lines/photo "
          f"{np.median([r['n_lines'] for r in rows]):5.0f}" + (f" (LSD {np.median(lsd):5.0f})" if lsd else "")
          + f"  z within 1.96: {np.mean(z < 1.96) if z.size else float('nan'):6.1%} of {z.size:5d}, beyond 3: "
          f"{np.mean(z > 3) if z.size else float('nan'):5.1%}  ECDF(p) - p max {excess:+.3f}  "
          f"p < {CONVICTION_P:.4f}: {int(np.sum(p < CONVICTION_P))}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=Path("/work/shared/data/real"))
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    items = photos(args.corpus)
    if not items:
        print("corpus absent")
        sys.exit(0)
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(run_one, items))
    for name in SETS:
        _report(name, [r for r in rows if r["set"] == name])
    _report("all authentic", rows)
    _homogeneity(rows)
    for r in rows:
        if r["status"] == "ok" and r["p"] < CONVICTION_P:
            print(f"  called a splice: {r['set']}/{r['file']} p = {r['p']:.3g}")


if __name__ == "__main__":
    main()
