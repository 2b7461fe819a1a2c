"""How well any block test could localise a pasted square with these references: the prnu local test's ceiling.

Usage: ``python benchmarks/prnu_local_ceiling.py --dresden DIR [--workers 2] [--out cases.json]``

``DIR`` holds the test data of ``polimi-ispl/prnu-python`` (``ff-jpg/``: ten
flat-field photos per unit; ``nat-jpg/``: natural photos), read where it lies
and never copied; without it this says so and exits 0. Any folder laid out the
same way serves (``UNIT_N_anything.JPG``, the unit being the first three
fields; e.g. a folder of links to another camera set's references and
photos). The cases are calibration's manipulation cases (:func:`forensics_plugins.prnu.calibrate.manipulation_jobs`,
same seed): each natural photo untouched (as written, and re-saved at JPEG
92) and with squares of 256, 384 and 512 px pasted from another unit's
photo, saved at JPEG 92; each is tested with its own unit's fingerprint,
estimated from that unit's flat-field photos (ten in the Dresden data).

Each photo's block map is the detector's (:func:`forensics_plugins.prnu.calibrate.tested_case`:
blocks of 256 px every 64 px). A block's standardised deficit is
``z = (rho_hat - rho) / sigma_1``: its predicted correlation less the
measured one, over the spread the photo's blocks show about the prediction
(``sigma_1^2 = sigma_0^2 + (tau rho_hat)^2``). Where the block lacks the
fingerprint, ``z`` has mean ``rho_hat / sigma_1`` (the block's SNR);
where it has it, mean 0.

Printed, per square size:

* the SNR of the blocks that lie within the pasted square (the 256 px
  block nearest it when none lies wholly inside), median and quartiles;
* the **oracle**: the statistic of a test told where the square is (the
  largest sum of ``z`` over the decidable ones of non-overlapping blocks
  inside it, over the root of their number), and the share of pastes where it exceeds the threshold a
  search over the photo must use: the 95th percentile, over the untouched
  photos, of the same statistic's largest value anywhere in the photo (5 %
  of untouched photos flagged). A test that does not know where to look
  cannot do better than this share, whatever its decision rule;
* what the detector does today: the share of pastes localised with pixel F1
  at least 0.5, and of untouched photos with a region flagged (as in
  ``calibration.json``).

First, how good the fingerprints themselves are: per unit, the correlation
of the fingerprints estimated from its even- and odd-numbered references
(split-half ``r``), the reliability of the estimate from all of them
(Spearman-Brown, ``2 r / (1 + r)``) and its root, the estimate's expected
correlation with the unit's true fingerprint. A block's SNR scales with that
correlation: a better fingerprint (more references) raises every figure
below.

Issue 43 asks for F1 >= 0.5 on 70 % of pasted squares of 256 px or more with at
most 5 % of untouched photos flagged.
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from forensics_plugins.prnu.calibrate import SIZES, _fingerprint, _unit, manipulation_jobs, tested_case
from forensics_plugins.prnu.spec import DEFAULT_PARAMS

# The detector's block and grid step (calibration tests the cases with them).
BLOCK = DEFAULT_PARAMS["block"]
STEP = BLOCK // 4


def _deficit(local) -> tuple[np.ndarray, np.ndarray]:
    """Per block, the standardised deficit ``z`` and the SNR ``rho_hat / sigma_1`` (undecidable blocks: NaN)."""
    sigma1 = np.sqrt(local.sigma0 ** 2 + (local.tau * local.predicted) ** 2)
    z = np.where(local.decidable, (local.predicted - local.rho) / sigma1, np.nan)
    snr = np.where(local.decidable, local.predicted / sigma1, np.nan)
    return z, snr


def _tiled(z: np.ndarray, blocks: int) -> np.ndarray:
    """For every placement on the grid, the sum of ``z`` over the decidable blocks of ``blocks x blocks``
    non-overlapping ones, over the root of their number (a standard normal where every block has the
    fingerprint); NaN where none is decidable."""
    d = BLOCK // STEP
    span = (blocks - 1) * d
    if z.shape[0] <= span or z.shape[1] <= span:
        return np.full((0, 0), np.nan)
    total = np.zeros((z.shape[0] - span, z.shape[1] - span))
    count = np.zeros_like(total)
    for i in range(blocks):
        for j in range(blocks):
            part = z[i * d: i * d + total.shape[0], j * d: j * d + total.shape[1]]
            total += np.nan_to_num(part)
            count += np.isfinite(part)
    return np.divide(total, np.sqrt(count), out=np.full_like(total, np.nan), where=count > 0)


def _inside(side: int, y: int, x: int, shape: tuple[int, int]) -> tuple[range, range]:
    """Grid rows and columns of the blocks lying wholly inside the square; the nearest block when none does."""
    def axis(start: int, n: int) -> range:
        first = -(-start // STEP)
        last = (start + side - BLOCK) // STEP
        if last < first:
            nearest = int(np.clip(round((start + (side - BLOCK) / 2) / STEP), 0, n - 1))
            return range(nearest, nearest + 1)
        return range(first, min(last, n - 1) + 1)
    return axis(y, shape[0]), axis(x, shape[1])


def run_one(job: tuple) -> dict:
    """One case: the detector's own result, and the block statistics the ceiling needs."""
    host, donor, side, _, _, save, _ = job
    case = tested_case(job)
    local, peak, mask = case.local, case.peak, case.mask
    z, snr = _deficit(local)
    record = {"host": Path(host).name, "donor": Path(donor).name if donor else None, "side": side, "save": save,
              "flagged": bool(case.found.any()), "f1": case.f1, "rotation": peak.rotation,
              "anywhere": {str(n): float(np.nanmax(t)) if np.isfinite(t).any() else None
                           for n in (1, 2) if (t := _tiled(z, n)).size}}
    if donor is not None:
        # The square where the turned grid holds it (the map is on the grid turned to the fingerprint's).
        ty, tx = np.nonzero(np.rot90(mask, k=peak.rotation // 90))
        rows, cols = _inside(side, int(ty.min()), int(tx.min()), z.shape)
        sub_z, sub_snr = z[np.ix_(rows, cols)], snr[np.ix_(rows, cols)]
        d = BLOCK // STEP
        n = 2 if (len(rows) > d and len(cols) > d) else 1
        record["snr"] = [float(v) for v in sub_snr.ravel() if np.isfinite(v)]
        tiled = _tiled(sub_z, n)
        record["oracle"] = {"blocks": n, "z": float(np.nanmax(tiled)) if np.isfinite(tiled).any() else None}
    return record


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dresden", type=Path, required=True, help="folder holding ff-jpg/ and nat-jpg/")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--work", type=Path, default=Path("benchmarks/out/prnu_ceiling"),
                    help="where the fingerprints are kept between runs")
    ap.add_argument("--out", type=Path, help="save every case's record here (JSON)")
    args = ap.parse_args()
    flat = sorted((args.dresden / "ff-jpg").glob("*.JPG"))
    natural = sorted((args.dresden / "nat-jpg").glob("*.JPG"))
    if not flat or not natural:
        print(f"{args.dresden}: no ff-jpg/ or nat-jpg/ photos (the test data of polimi-ispl/prnu-python): "
              "nothing measured")
        return 0
    units = sorted({_unit(p) for p in flat})
    args.work.mkdir(parents=True, exist_ok=True)
    with ProcessPoolExecutor(args.workers) as pool:
        todo = [u for u in units if not (args.work / f"{u}.npy").is_file()]
        for unit, k in zip(todo, pool.map(_fingerprint, [[str(p) for p in flat if _unit(p) == u] for u in todo])):
            np.save(args.work / f"{unit}.npy", k)
        fingerprints = {u: str(args.work / f"{u}.npy") for u in units}
        groups = [[str(p) for p in flat if _unit(p) == u] for u in units]
        halves = list(pool.map(_fingerprint, [g[0::2] for g in groups] + [g[1::2] for g in groups]))
    print("fingerprint quality (split-half):")
    for unit, even, odd in zip(units, halves[:len(units)], halves[len(units):]):
        r = float(np.corrcoef(even.ravel(), odd.ravel())[0, 1])
        reliability = 2 * r / (1 + r)
        print(f"  {unit}: split-half r {r:.3f}, reliability of all {len(flat) // len(units)} "
              f"{reliability:.3f}, expected correlation with the true fingerprint {np.sqrt(max(reliability, 0)):.2f}")
    with ProcessPoolExecutor(args.workers) as pool:
        records = list(pool.map(run_one, manipulation_jobs(natural, fingerprints)))
    if args.out:
        args.out.write_text(json.dumps(records, indent=1))
    untouched = [r for r in records if r["donor"] is None]
    print(f"{len(records)} cases from {args.dresden}: {len(untouched)} untouched, "
          f"{len(records) - len(untouched)} pasted; fingerprints from {len(flat) // len(units)} flat-field photos "
          f"per unit")
    thresholds = {}
    for n in ("1", "2"):
        values = [r["anywhere"].get(n) for r in untouched if r["anywhere"].get(n) is not None]
        thresholds[int(n)] = float(np.quantile(values, 0.95))
        print(f"  untouched photos, largest statistic over {int(n) ** 2} block(s) anywhere: median "
              f"{np.median(values):.2f}, 95th percentile {thresholds[int(n)]:.2f} (the search's threshold)")
    print(f"  detector today: untouched photos with a region flagged {np.mean([r['flagged'] for r in untouched]):.0%}")
    for side in SIZES:
        pasted = [r for r in records if r["donor"] is not None and r["side"] == side]
        known = [r for r in pasted if r.get("oracle") and r["oracle"]["z"] is not None]
        snr = np.concatenate([r["snr"] for r in known if r["snr"]]) if known else np.zeros(0)
        oracle = [r["oracle"]["z"] > thresholds[r["oracle"]["blocks"]] for r in known]
        undecidable = len(pasted) - len(known)
        print(f"  {side} px: {len(pasted)} pastes; block SNR inside the square median {np.median(snr):.2f} "
              f"(quartiles {np.quantile(snr, 0.25):.2f}-{np.quantile(snr, 0.75):.2f}); oracle above the search's "
              f"threshold {sum(oracle)}/{len(pasted)} ({sum(oracle) / len(pasted):.0%}; {undecidable} with no "
              f"decidable block there); detector today F1 >= 0.5 on "
              f"{np.mean([r['f1'] >= 0.5 for r in pasted]):.0%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
