"""Fitting the prnu detector's likelihood-ratio models on real photos, and measuring them (``calibration.json``).

Run on the Dresden test data of ``polimi-ispl/prnu-python`` (``ff-jpg``: ten
flat-field photos of each of six Nikon cameras, two units each of the D70,
D70s and D200; ``nat-jpg``: natural photos of the same units) and on a
folder of other cameras' photos (the shared real corpus)::

    python -m forensics_plugins.prnu.calibrate --dresden DIR --others DIR --out calibration.json

Nothing of the data is copied; the output holds the fitted models, the
figures they were validated with and the files' hashes.

* Source: every natural photo against every unit's fingerprint (same unit:
  Hp; other unit: Hd) and every other camera's photo against every
  fingerprint (Hd), scored by the best alignment's single-test z. Hd's
  Student t (its tail from the comparisons with another unit of the same
  model) and Hp's log-normal are refitted leaving each photo out, the
  left-out photo's comparisons scored, and Cllr, Cllr_min (lir) and the ELUB
  bounds computed on those cross-validated LRs.
* Manipulation: each natural photo, untouched (as the camera wrote it, and
  re-saved at JPEG 92) and with a square of 256, 384 or 512 px pasted from a
  natural photo of another unit (at two positions drawn from a fixed seed),
  saved at JPEG 92; scored by the largest summed block log-likelihood ratio,
  calibrated by lir's logistic regression with leave-one-host-out
  cross-validation; pixel F1 of the flagged regions against the pasted square.
"""

from __future__ import annotations

import argparse
import hashlib
import io
import json
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image
from scipy.stats import ks_2samp, norm, t

from .alignment import aligned, best_alignment, single_test_z
from .pce import Peak
from .fingerprint import estimate
from .local import LocalMap, boxes, local_map, regions
from .residual import test_residual
from .spec import DEFAULT_PARAMS, VERSION

SIZES = (256, 384, 512)
QUALITY = 92
SEED = 20261128
# Degrees of freedom tried for Hd's tail, from very heavy to near-normal.
DF_GRID = (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 7.0, 10.0, 15.0, 30.0, 100.0)
_LN10 = math.log(10.0)


def _unit(path: Path) -> str:
    """``Nikon_D70s_1_22750.JPG`` -> ``Nikon_D70s_1``."""
    return "_".join(path.stem.split("_")[:3])


def _model(unit: str) -> str:
    return unit.rsplit("_", 1)[0]


def _pixels(path: Path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"))


def _jpeg(pixels: np.ndarray) -> np.ndarray:
    buffer = io.BytesIO()
    Image.fromarray(pixels).save(buffer, "JPEG", quality=QUALITY)
    buffer.seek(0)
    with Image.open(buffer) as image:
        return np.asarray(image.convert("RGB"))


def _fingerprint(files: list[str]) -> np.ndarray:
    return estimate(_pixels(Path(f)) for f in files).k


def _attribution(job: tuple[str, dict[str, str]]) -> list[tuple[str, str, float, int]]:
    """(photo, unit, PCE, alignments searched) of one photo against every fingerprint file."""
    path, fingerprints = job
    try:
        pixels = _pixels(Path(path))
    except (OSError, ValueError):
        return []
    residual, intensity = test_residual(pixels)
    out = []
    for unit, fp in fingerprints.items():
        peak = best_alignment(intensity * residual, np.load(fp))
        if peak is not None:
            out.append((path, unit, peak.pce, peak.searched))
    return out


def manipulation_jobs(natural: list[Path], fingerprints: dict[str, str]) -> list[tuple]:
    """The manipulation cases, drawn from :data:`SEED`: per natural photo, untouched twice and two pastes of each size.

    Parameters
    ----------
    natural : list of Path
        The natural photos, sorted.
    fingerprints : dict of str to str
        Each unit's fingerprint file (``.npy``).

    Returns
    -------
    list of tuple
        ``(host, donor or None, side, y, x, save, fingerprint file)``: the
        square of ``side`` pixels at row ``y``, column ``x`` comes from the
        same place of a natural photo of another unit; ``save`` is
        ``original`` (untouched, as the camera wrote it) or ``jpeg92``.
    """
    rng = np.random.default_rng(SEED)
    jobs: list[tuple] = []
    for host in natural:
        shape = _pixels(host).shape
        donors = [d for d in natural if _unit(d) != _unit(host) and _pixels(d).shape == shape]
        fp = fingerprints[_unit(host)]
        jobs += [(str(host), None, 0, 0, 0, save, fp) for save in ("original", "jpeg92")]
        for side in SIZES:
            for _ in range(2):
                donor = donors[int(rng.integers(len(donors)))]
                y = int(rng.integers(0, shape[0] - side))
                x = int(rng.integers(0, shape[1] - side))
                jobs.append((str(host), str(donor), side, y, x, "jpeg92", fp))
    return jobs


def case_pixels(job: tuple) -> tuple[np.ndarray, np.ndarray]:
    """A manipulation case's pixels, shape (H, W, 3) uint8, and its true mask, shape (H, W) bool."""
    host, donor, side, y, x, save, _ = job
    pixels = _pixels(Path(host))
    mask = np.zeros(pixels.shape[:2], bool)
    if donor is not None:
        pixels = pixels.copy()
        pixels[y:y + side, x:x + side] = _pixels(Path(donor))[y:y + side, x:x + side]
        mask[y:y + side, x:x + side] = True
    if save == "jpeg92":
        pixels = _jpeg(pixels)
    return pixels, mask


@dataclass(frozen=True)
class LocalCase:
    """A manipulation case tested as the detector tests a photo.

    Attributes
    ----------
    local : LocalMap
        The block map, on the photo's grid turned to the fingerprint's.
    peak : Peak
        The alignment found.
    mask, found : ndarray of bool, shape (H, W)
        The true pasted square and the flagged regions' boxes, on the stored grid.
    score : float
        The largest window log-likelihood ratio (the calibrated score).
    f1 : float
        Pixel F1 of ``found`` against ``mask`` (1 when both are empty).
    """

    local: LocalMap
    peak: Peak
    mask: np.ndarray
    found: np.ndarray
    score: float
    f1: float


def tested_case(job: tuple) -> LocalCase:
    """Run the detector's global and local tests on one case of :func:`manipulation_jobs`."""
    pixels, mask = case_pixels(job)
    k = np.load(job[-1])
    residual, intensity = test_residual(pixels)
    peak = best_alignment(intensity * residual, k)
    (turned_residual, turned_intensity), kk = aligned((residual, intensity), peak, k)
    p = DEFAULT_PARAMS
    local = local_map(turned_residual, turned_intensity, kk, p["block"], p["block"] // 4)
    flagged, best = regions(local, p["region_llr"])
    found = np.zeros(mask.shape, bool)
    for x0, y0, x1, y1 in boxes(flagged, local.block, local.step, peak.rotation, turned_residual.shape):
        found[y0:y1, x0:x1] = True
    tp = float((found & mask).sum())
    f1 = 2 * tp / (found.sum() + mask.sum()) if (found.sum() + mask.sum()) else 1.0
    return LocalCase(local, peak, mask, found, best, f1)


def _local(job: tuple[str, str | None, int, int, int, str, str]) -> dict:
    """One manipulation case: host, donor (None: untouched), side, position, save and fingerprint file, scored."""
    host, donor, side, y, x, save, _ = job
    case = tested_case(job)
    return {"host": Path(host).name, "donor": Path(donor).name if donor else None, "side": side, "y": y, "x": x,
            "save": save, "pce": case.peak.pce, "score": case.score, "flagged": bool(case.found.any()),
            "f1": case.f1, "decidable": float(case.local.decidable.mean())}


def _lir():
    import lir.algorithms.bayeserror as bayeserror
    import lir.metrics as metrics
    from lir.algorithms.logistic_regression import LogitCalibrator
    from lir.data.models import LLRData

    return bayeserror, metrics, LogitCalibrator, LLRData


def _costs(llrs: np.ndarray, y: np.ndarray) -> dict[str, float]:
    bayeserror, metrics, _, LLRData = _lir()
    data = LLRData(features=llrs, labels=y)
    lower, upper = bayeserror.elub(llrs, y)
    return {"cllr": round(float(metrics.cllr(data)), 4), "cllr_min": round(float(metrics.cllr_min(data)), 4),
            "elub": [round(float(lower), 3), round(float(upper), 3)]}


def _fit_attribution(z: np.ndarray, y: np.ndarray, same_model: np.ndarray) -> dict[str, float]:
    """Hd: Student t, centre and scale from every other-camera comparison, degrees of freedom from the same-model
    ones (profile likelihood: cameras of one model share traces that thicken the tail); Hp: log-normal."""
    hd = z[y == 0]
    loc, scale = float(hd.mean()), float(hd.std(ddof=1))
    tail = z[same_model]
    df = max(DF_GRID, key=lambda d: t.logpdf(tail, d, loc=loc, scale=scale).sum()) if len(tail) else DF_GRID[-1]
    logs = np.log(z[(y == 1) & (z > 0)])
    return {"hd_df": float(df), "hd_loc": loc, "hd_scale": scale,
            "hp_mu": float(logs.mean()), "hp_sigma": float(logs.std(ddof=1))}


def _attribution_llr(model: dict[str, float], z: float) -> float:
    hd = t.logpdf(z, model["hd_df"], loc=model["hd_loc"], scale=model["hd_scale"])
    if z <= 0:
        return -50.0
    hp = norm.logpdf(math.log(z), model["hp_mu"], model["hp_sigma"]) - math.log(z)
    return float(np.clip((hp - hd) / _LN10, -50.0, 50.0))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dresden", type=Path, required=True, help="folder holding ff-jpg/ and nat-jpg/")
    parser.add_argument("--others", type=Path, nargs="*", default=[], help="folders of other cameras' photos")
    parser.add_argument("--work", type=Path, required=True,
                        help="scratch folder for the fingerprints and the scores (reused when there; empty it to rescore)")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    flat = sorted((args.dresden / "ff-jpg").glob("*.JPG"))
    natural = sorted((args.dresden / "nat-jpg").glob("*.JPG"))
    if not flat or not natural:
        print(f"{args.dresden}: no ff-jpg/ or nat-jpg/ photos", file=sys.stderr)
        return 1
    units = sorted({_unit(p) for p in flat})
    args.work.mkdir(parents=True, exist_ok=True)
    # MICC-F220's tampered copies repeat their originals' (``_scale``) noise: only the originals count.
    others = sorted(p for folder in args.others for p in folder.rglob("*")
                    if p.suffix.lower() in (".jpg", ".jpeg", ".png", ".tif") and "Nikon_D" not in p.name
                    and "tamp" not in p.name)
    with ProcessPoolExecutor(args.workers) as pool:
        groups = [[str(p) for p in flat if _unit(p) == u] for u in units]
        if not all((args.work / f"{u}.npy").is_file() for u in units):
            for unit, k in zip(units, pool.map(_fingerprint, groups)):
                np.save(args.work / f"{unit}.npy", k)
        fps = {u: str(args.work / f"{u}.npy") for u in units}
        scored = args.work / "attribution.json"
        rows = [tuple(r) for r in json.loads(scored.read_text())] if scored.is_file() else []
        seen = {r[0] for r in rows}
        todo = [(str(p), fps) for p in natural + others if str(p) not in seen]
        rows += [r for rs in pool.map(_attribution, todo) for r in rs]
        wanted = {str(p) for p in natural + others}
        rows = [r for r in rows if r[0] in wanted]
        scored.write_text(json.dumps(rows))
        done = args.work / "manipulation.json"
        if done.is_file():
            cases = json.loads(done.read_text())
        else:
            cases = list(pool.map(_local, manipulation_jobs(natural, fps)))
            done.write_text(json.dumps(cases))

    photos = np.array([Path(p).name for p, _, _, _ in rows])
    z = np.array([single_test_z(Peak(pce, (0, 0), searched)) for _, _, pce, searched in rows])
    photo_unit = [_unit(Path(p)) if Path(p).name.startswith("Nikon_D") else "other" for p, _, _, _ in rows]
    y = np.array([int(pu == u) for pu, (_, u, _, _) in zip(photo_unit, rows)])
    same_model = np.array([pu != "other" and _model(pu) == _model(u) and pu != u
                           for pu, (_, u, _, _) in zip(photo_unit, rows)])
    cv = np.zeros(len(z))
    for name in sorted(set(photos)):
        out = photos == name
        model = _fit_attribution(z[~out], y[~out], same_model[~out])
        cv[out] = [_attribution_llr(model, v) for v in z[out]]
    attribution = _fit_attribution(z, y, same_model)
    costs = _costs(cv, y)
    attribution.update(lower=costs["elub"][0], upper=costs["elub"][1])
    lrs_hp = cv[y == 1]
    bounded = np.clip(cv, costs["elub"][0], costs["elub"][1])
    source_figures = {
        **costs, "n_hp": int(y.sum()), "n_hd": int((y == 0).sum()), "n_hd_same_model": int(same_model.sum()),
        "hp_lr_at_least_1000": round(float(np.mean(bounded[y == 1] >= 3.0)), 4),
        "hd_same_model_lr_at_most_1": round(float(np.mean(bounded[same_model] <= 0.0)), 4),
        "hd_lr_at_most_1": round(float(np.mean(bounded[y == 0] <= 0.0)), 4),
        "hp_z": sorted(round(float(v), 2) for v in z[y == 1]),
        "hd_same_model_z": sorted(round(float(v), 2) for v in z[same_model]),
        "hd_other_z_max": round(float(z[(y == 0) & ~same_model].max()), 2),
        "ks_same_model_vs_other_p": round(float(ks_2samp(z[same_model], z[(y == 0) & ~same_model]).pvalue), 4),
        "hp_unbounded_log10_lr_min": round(float(lrs_hp.min()), 2),
    }

    _, _, LogitCalibrator, _ = _lir()
    score = np.array([c["score"] for c in cases])
    spliced = np.array([int(c["donor"] is not None) for c in cases])
    hosts = np.array([c["host"] for c in cases])

    def logit(xs, ys):
        cal = LogitCalibrator().fit(xs, ys)
        return float(cal._logit.intercept_[0]) / _LN10, float(cal._logit.coef_[0, 0]) / _LN10

    local_cv = np.zeros(len(score))
    for name in sorted(set(hosts)):
        out = hosts == name
        a, b = logit(score[~out], spliced[~out])
        local_cv[out] = a + b * score[out]
    intercept, slope = logit(score, spliced)
    local_costs = _costs(local_cv, spliced)
    by_size = {str(s): {"n": int(sum(1 for c in cases if c["side"] == s and c["donor"])),
                        "f1_at_least_half": round(float(np.mean([c["f1"] >= 0.5 for c in cases
                                                                 if c["side"] == s and c["donor"]])), 4)}
               for s in SIZES}
    untouched = [c for c in cases if c["donor"] is None]
    manipulation = {"intercept": intercept, "slope": slope, "lower": min(local_costs["elub"][0], 0.0),
                    "upper": max(local_costs["elub"][1], 0.0)}
    local_figures = {**local_costs, "n_spliced": int(spliced.sum()), "n_untouched": len(untouched),
                     "untouched_flagged": round(float(np.mean([c["flagged"] for c in untouched])), 4),
                     "f1_at_least_half": by_size,
                     "region_llr": DEFAULT_PARAMS["region_llr"]}
    digest = hashlib.sha256()
    for p in flat + natural + others:
        digest.update(p.read_bytes())
    result = {
        "format": "forensics-prnu-calibration-1",
        "attribution": attribution,
        "manipulation": manipulation,
        "data": {
            "source": "Dresden Image Database photos of six Nikon units (D70, D70s, D200; two units each) from the "
                      "test data of polimi-ispl/prnu-python: 10 flat-field references per unit and "
                      f"{len(natural)} natural photos; {len(others)} photos of other cameras (the shared real "
                      "corpus). Cross-validated leaving one photo (source) or one host photo (manipulation) out.",
            "content_sha256": digest.hexdigest(), "detector_version": VERSION, "seed": SEED,
            "source_figures": source_figures, "manipulation_figures": local_figures,
        },
        "cases": cases,
    }
    args.out.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    print(json.dumps({"source": source_figures, "manipulation": local_figures}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
