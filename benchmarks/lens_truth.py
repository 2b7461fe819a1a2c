"""Does the lens detector's ``k1 ± stderr`` hold against known truth on real photos?

Usage: ``python benchmarks/lens_truth.py [--shared ../shared/data] [--workers 2] [--module NAME] [--verbose]``

Runs the lens detector on real photos whose distortion is known, or known
to be shared, and prints how its stated uncertainty holds (issue 37):

* **chessboards**: the five OpenCV calibration views of
  ``calibration/`` (OpenCV's own calibration of that camera, in its README,
  as truth). The truth is the detector's model fitted by least squares to
  OpenCV's distortion map over the points of the lines the detector used:
  a real lens has more terms than the model, so its best ``k1`` depends on
  where the lines lie;
* **undistorted chessboards**: the same views undistorted with that
  calibration (``cv2.undistort``, same camera matrix): true distortion 0;
* **lensfun-known photos**: the real corpus's building and chart photos
  whose EXIF names a camera and lens that lensfun (the metadata plugin's
  lookup) knows, truth its prediction for the photo's geometry. Left out:
  the Panasonic DMC-LX3, whose JPEGs are corrected for distortion in the
  camera (lensfun's calibration is of its raw files);
* **one-camera series**: the corpus's photos grouped by camera, focal
  length and pixel size (``opensfm_lund`` is one camera; ``opensfm_berlin``
  another of the same model), with Cochran's ``Q = sum((k1_i - mean)^2 /
  se_i^2)`` on ``n - 1`` degrees of freedom per series, ``Q/df`` near 1
  when the stated errors cover the spread between photos of one lens.

For the first three it prints the RMS of the normalised error ``(measured -
truth) / stderr`` (target 0.8-1.3) and the share within +-1.96 (target at
least 90 %). Whether the published ``k1`` is the one-term model's
(``k2`` held at 0, ``k2_stderr`` 0) or a two-term model's is read from the
finding, and the truth is computed in the same model, so an older copy of
the plugin (``--module``) is judged on its own terms. It also prints how
often the detector ran (status ok) on the building photos and how many
authentic photos it called inconsistent.

The photos are only read, never copied or written; without
``../shared/data`` it prints "data absent" and exits 0.
"""

from __future__ import annotations

import argparse
import csv
import importlib
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from scipy import stats
from scipy.optimize import least_squares

# OpenCV's calibration of the chessboard camera (calibration/README.md: its
# regression test's values, all thirteen views).
CAMERA = np.array([[532.80992189, 0.0, 342.4952186], [0.0, 532.93346422, 233.8879292], [0.0, 0.0, 1.0]])
DISTORTION = np.array([-2.81325576e-01, 2.91130406e-02, 1.21234330e-03, -1.40825372e-04, 1.54865844e-01])
SETS = (
    "authentic_buildings/dresden_prnu-python",
    "authentic_buildings/metadata-extractor-images",
    "authentic_buildings/metadata-extractor-images_rotated",
    "authentic_buildings/opensfm_lund",
    "authentic_buildings/opensfm_berlin",
    "authentic_charts/digicam_corpus",
)
IN_CAMERA_CORRECTED = ("DMC-LX3",)


def cases(shared: Path) -> list[dict]:
    """Every photo to run, with how its truth is known."""
    out = []
    for path in sorted((shared / "calibration").glob("left0*.jpg")):
        out.append({"kind": "chessboard", "path": str(path), "group": ""})
        out.append({"kind": "undistorted chessboard", "path": str(path), "group": ""})
    for name in SETS:
        folder = shared / "real" / name
        if not (folder / "truth.csv").exists():
            continue
        with (folder / "exif.csv").open(newline="") as f:
            exif = {row["file"]: row for row in csv.DictReader(f)}
        with (folder / "truth.csv").open(newline="") as f:
            for row in csv.DictReader(f):
                if row["label"] != "authentic":
                    continue
                e = exif.get(row["file"], {})
                size = "x".join(sorted((e.get("width", "0"), e.get("height", "0")), key=int, reverse=True))
                camera = f"{e.get('make', '')} {e.get('model', '')}".strip() or name.split("/")[-1]
                out.append({"kind": "corpus", "set": name, "path": str(folder / row["file"]),
                            "group": f"{camera}, {e.get('focal_length_mm', '')} mm, {size}"})
    return out


def _fit_map(distorted_px: np.ndarray, undistorted_px: np.ndarray, shape: tuple[int, int],
             two_term: bool) -> np.ndarray:
    """The detector's model ``(k1, k2, cx, cy)`` fitted to a distortion map, up to an affine map.

    Straightness does not change under an affine map of the undistorted
    image, so the truth allows one (as the calibration README's conversion does).
    """
    h, w = shape
    scale = max(h, w) / 2.0
    centre = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    d = (distorted_px - centre) / scale
    u = (undistorted_px - centre) / scale

    def residual(b: np.ndarray) -> np.ndarray:
        k1, k2, cx, cy = b[:4]
        q = d - (cx, cy)
        r2 = np.einsum("ij,ij->i", q, q)
        model = (cx, cy) + q * (1.0 + k1 * r2 + (k2 * r2 * r2 if two_term else 0.0))[:, None]
        return (model @ (np.eye(2) + b[4:8].reshape(2, 2)).T + b[8:10] - u).ravel()

    return least_squares(residual, np.zeros(10)).x[:4]


def run(case: dict, module: str) -> dict:
    import cv2

    from forensics_core.evidence import load_evidence

    detector = importlib.import_module(f"{module}.detector")
    spec = importlib.import_module(f"{module}.spec")
    evidence = load_evidence(Path(case["path"]))
    luma = evidence.luma
    if case["kind"] == "undistorted chessboard":
        luma = cv2.undistort(luma.astype(np.float32), CAMERA, DISTORTION, None, CAMERA).astype(np.float64)
    result = detector.analyse(luma, spec.DEFAULT_PARAMS)
    model = result.details.get("global_model") or {}
    out = {**case, "status": result.status.value, "verdict_p": result.p_value,
           "k1": model.get("k1"), "se": model.get("k1_stderr"),
           "two_term": bool(model) and not (model.get("k2") == 0 and model.get("k2_stderr") == 0)}
    if case["kind"] == "chessboard" and out["k1"] is not None:
        used = [np.asarray(line["points_px"]) for line in result.details["lines"]
                if line["informative"] and not line["outlier"] and not line["flagged"]]
        pts = np.vstack(used)
        und = cv2.undistortPoints(pts.reshape(-1, 1, 2), CAMERA, DISTORTION, P=CAMERA).reshape(-1, 2)
        out["truth"] = float(_fit_map(pts, und, luma.shape[:2], out["two_term"])[0])
    elif case["kind"] == "undistorted chessboard":
        out["truth"] = 0.0
    elif case["kind"] == "corpus" and out["k1"] is not None:
        out["truth"] = _lensfun_truth(evidence, out["two_term"])
    return out


def _lensfun_truth(evidence, two_term: bool) -> float | None:
    """lensfun's prediction of the photo's k1, or None when lensfun does not know its lens."""
    from forensics_plugins.metadata.conversion import predict, unit_scale
    from forensics_plugins.metadata.lensdb import lookup

    exif = evidence.info.exif
    if any(name in (exif.model or "") for name in IN_CAMERA_CORRECTED):
        return None
    found = lookup(exif.make, exif.model, exif.lens_model, exif.focal_length_mm)
    if found.data is None:
        return None
    lens = found.data
    w, h = evidence.info.width, evidence.info.height
    scale = unit_scale(max(w, h) / min(w, h), lens.calibration_aspect, lens.calibration_crop, lens.camera_crop)
    prediction = predict(lens.model, lens.terms, w, h, scale)
    if prediction is None:
        return None
    return prediction.k1 if two_term else prediction.k1_one_term


def _normalised(rows: list[dict], label: str, verbose: bool) -> np.ndarray:
    z = np.array([(r["k1"] - r["truth"]) / r["se"] for r in rows])
    if verbose:
        for r, zi in zip(rows, z):
            print(f"    {Path(r['path']).name[:34]:34s} k1 {r['k1']:+.4f} ± {r['se']:.4f}  truth {r['truth']:+.4f}  "
                  f"z {zi:+.2f}")
    if z.size:
        print(f"  {label:28s} n {z.size:3d}  RMS z {np.sqrt(np.mean(z**2)):5.2f}  within ±1.96 "
              f"{np.mean(np.abs(z) < 1.96):5.0%}  max |z| {np.max(np.abs(z)):5.2f}")
    return z


def report(rows: list[dict], verbose: bool) -> None:
    measured = [r for r in rows if r["status"] == "ok" and r["k1"] is not None and (r["se"] or 0) > 0]
    print("known distortion: normalised error (measured - truth) / stated error (target RMS 0.8-1.3, >= 90 % "
          "within ±1.96)")
    pooled = []
    for kind in ("chessboard", "undistorted chessboard", "corpus"):
        chosen = [r for r in measured if r["kind"] == kind and r.get("truth") is not None]
        pooled.append(_normalised(chosen, "lensfun-known photos" if kind == "corpus" else kind + "s", verbose))
    z = np.concatenate(pooled)
    print(f"  {'all known':28s} n {z.size:3d}  RMS z {np.sqrt(np.mean(z**2)):5.2f}  within ±1.96 "
          f"{np.mean(np.abs(z) < 1.96):5.0%}")
    print("one camera, one zoom: Cochran's Q/df of k1 (target <= 1.5)")
    groups: dict[str, list[dict]] = {}
    for r in measured:
        if r["kind"] == "corpus":
            groups.setdefault(r["group"], []).append(r)
    q_total = df_total = 0.0
    for group, members in sorted(groups.items()):
        if len(members) < 2:
            continue
        k = np.array([m["k1"] for m in members])
        w = np.array([m["se"] for m in members]) ** -2.0
        mean = float(np.sum(w * k) / np.sum(w))
        q = float(np.sum(w * (k - mean) ** 2))
        df = len(k) - 1
        q_total, df_total = q_total + q, df_total + df
        print(f"  {group[:50]:50s} n {len(k):2d}  k1 {mean:+.4f}  range {k.min():+.3f}..{k.max():+.3f}  "
              f"median se {np.median(1 / np.sqrt(w)):.4f}  Q/df {q / df:5.2f}  p {stats.chi2.sf(q, df):.2g}")
    if df_total:
        print(f"  {'pooled':50s} df {int(df_total):2d}  Q/df {q_total / df_total:5.2f}")
    buildings = [r for r in rows if r["kind"] == "corpus" and r["set"].startswith("authentic_buildings")]
    corpus = [r for r in rows if r["kind"] == "corpus"]
    ok = sum(r["status"] == "ok" for r in buildings)
    called = [r for r in corpus if r["status"] == "ok" and r["verdict_p"] is not None and r["verdict_p"] < 0.01]
    print(f"status ok on building photos: {ok}/{len(buildings)} ({ok / max(len(buildings), 1):.0%}); authentic "
          f"photos called inconsistent (p < 0.01): {len(called)}/{len(corpus)}")
    for r in called:
        print(f"  {r['path']} p = {r['verdict_p']:.2g}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "data")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--module", default="forensics_plugins.lens_distortion",
                        help="the lens plugin package to measure (an older copy on PYTHONPATH, side by side)")
    parser.add_argument("--verbose", action="store_true", help="print every known-truth photo")
    args = parser.parse_args()
    todo = cases(args.shared)
    if not todo:
        print(f"data absent ({args.shared}): nothing measured")
        sys.exit(0)
    importlib.import_module(args.module)
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(run, todo, [args.module] * len(todo)))
    report(rows, args.verbose)


if __name__ == "__main__":
    main()
