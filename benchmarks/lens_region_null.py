"""Whether a region's lines read another lens than the rest of the photo, judged against the photo's own spread.

Usage: ``python benchmarks/lens_region_null.py [--suite /tmp/lens_splices] [--workers 2] [--tau0 0.02]
[--radius 0.35]``

Issue 37 asks the lens detector to speak on real splices. This measures the
best test the lines allow, once with the pasted piece known (its mask) and
once without it, on the ``lens-splices`` suite (built by ``forensics
validate lens-splices``; see :mod:`forensics_core.validation.lens_splices`):

* **the rest without the region.** A piece rich in long edges can hold most
  of the photo's informative lines, and then the lens fitted to the whole
  photo is the piece's own. So the lens is fitted again to the lines
  outside the region: a Student-t (the detector's ``DOF``) weighted least
  squares of the lines' departures ``delta_j`` on their sensitivities to
  ``(k1, k2, cx, cy)`` (the detector's final departures and gradient,
  linearised about its global fit, with its priors on ``k2`` and the
  centre), and each line's departure from that fit with its variance;
* **the photo's own spread.** Real regions of one authentic photo depart
  from its lens by more than their lines' errors say (one facade bowing,
  curved objects sharing a region, a lens the model does not fit). The
  spread ``tau`` between spatial clusters of the rest's lines
  (DerSimonian-Laird, clusters of the lines within 0.35 of each other),
  combined with a floor ``--tau0``, is added to the region's error;
* **the statistic.** Per direction family of the region's lines (nearer
  horizontal or nearer vertical, at least two lines), the Student-t
  location of their departures over ``sqrt(se^2 + tau^2)``; the larger
  ``|z|`` of the two families.

With the piece known, a control is measured at its host's splices' masks.
Without it, the statistic is the largest over the regions a test would
weigh: the informative lines within ``--radius`` (normalised, half the
larger side) of each long line's midpoint. Printed per kind: the share of
cases with ``|z|`` above 2, 3 and 4 (piece known), and the share above the
controls' 95th percentile and maximum (piece unknown), with how many of
those regions hold a pasted line.

The detector's findings do not carry each line's sensitivity to the lens
parameters, so this wraps :func:`forensics_plugins.lens_distortion.consistency._departures`
for the run to keep its final call (the departures with every line refitted);
nothing the detector computes is changed. Without the suite folder it says
how to build it and exits 0. The photos and masks are only read.
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image
from scipy.special import gammaln

DEFAULT_SUITE = Path("/tmp/lens_splices")
KINDS = ("other_camera", "moved", "rescaled", "control")
#: Priors of (k1, k2, cx, cy) the detector fits with (its ``k2_prior_sd`` and ``centre_sd``).
PRIOR_SD = np.array([np.inf, 0.3, 0.05, 0.05])
CLUSTER_RADIUS = 0.35
IN_MASK_SHARE = 0.5
_GRID = np.linspace(-0.6, 0.6, 2401)


def _log_t(x: np.ndarray, s: np.ndarray, dof: float) -> np.ndarray:
    c = gammaln((dof + 1) / 2) - gammaln(dof / 2) - 0.5 * np.log(dof * np.pi)
    return c - np.log(s) - (dof + 1) / 2 * np.log1p((x / s) ** 2 / dof)


def t_location(d: np.ndarray, s: np.ndarray, dof: float) -> tuple[float, float]:
    """Maximum-likelihood Student-t location of ``d`` (scales ``s``) on a grid, and its curvature error."""
    ll = _log_t(d[:, None] - _GRID[None, :], s[:, None], dof).sum(axis=0)
    i = int(np.argmax(ll))
    if not 0 < i < _GRID.size - 1:
        return float(_GRID[i]), float("inf")
    h = _GRID[1] - _GRID[0]
    curvature = (ll[i + 1] - 2 * ll[i] + ll[i - 1]) / h**2
    return float(_GRID[i]), float(1 / np.sqrt(max(-curvature, 1e-12)))


def rest_fit(delta: np.ndarray, x: np.ndarray, var: np.ndarray, beta: np.ndarray, keep: np.ndarray, dof: float
             ) -> tuple[np.ndarray, np.ndarray]:
    """The lens of the lines ``keep``: Student-t IRLS of ``delta = x theta + e`` with the detector's priors.

    ``theta`` is the correction to the global fit ``beta`` (k1, k2, cx, cy);
    returns it and its covariance.
    """
    xk, yk, vk = x[keep], delta[keep], var[keep]
    prior_w = 1 / PRIOR_SD**2
    prior_mean = np.where(np.isfinite(PRIOR_SD), -beta, 0.0)
    w = np.ones(keep.sum())
    for _ in range(30):
        a = (xk * (w / vk)[:, None]).T @ xk + np.diag(prior_w)
        theta = np.linalg.solve(a, (xk * (w / vk)[:, None]).T @ yk + prior_w * prior_mean)
        new = (dof + 1) / (dof + (yk - xk @ theta) ** 2 / vk)
        if np.allclose(new, w, atol=1e-4):
            break
        w = new
    info = (xk * ((dof + 1) / (dof + 3) / vk)[:, None]).T @ xk + np.diag(prior_w)
    return theta, np.linalg.inv(info)


def _clusters(mid: np.ndarray, members: np.ndarray) -> list[np.ndarray]:
    left, out = list(members), []
    while left:
        group = [j for j in left if np.hypot(*(mid[j] - mid[left[0]])) <= CLUSTER_RADIUS]
        out.append(np.array(group))
        left = [j for j in left if j not in group]
    return out


def _dl_tau(m: list[float], se: list[float]) -> float:
    m, se = np.asarray(m), np.asarray(se)
    if m.size < 2:
        return float("nan")
    w = 1 / se**2
    q = np.sum(w * (m - np.sum(w * m) / w.sum()) ** 2)
    return float(np.sqrt(max(0.0, (q - (m.size - 1)) / (w.sum() - np.sum(w**2) / w.sum()))))


def region_z(lines: dict[str, np.ndarray], region: np.ndarray, tau0: float, dof: float) -> float:
    """The larger ``|z|`` of the region's two direction families against the rest's lens and the photo's spread."""
    theta, cov = rest_fit(lines["delta"], lines["x"], lines["var"], lines["beta"], ~region, dof)
    residual = lines["delta"] - lines["x"] @ theta
    s = np.sqrt(lines["var"] + np.einsum("ij,jk,ik->i", lines["x"], cov, lines["x"]))
    located = [t_location(residual[g], s[g], dof) for g in _clusters(lines["mid"], np.flatnonzero(~region))
               if len(g) >= 2]
    tau = _dl_tau([m for m, _ in located], [e for _, e in located])
    tau = tau0 if not np.isfinite(tau) else float(np.hypot(tau, tau0))
    best = 0.0
    for family in (lines["horizontal"], ~lines["horizontal"]):
        chosen = region & family
        if chosen.sum() >= 2:
            mu, se = t_location(residual[chosen], s[chosen], dof)
            best = max(best, abs(mu) / float(np.hypot(se, tau)))
    return best


def _in_mask(points: list[np.ndarray], mask: np.ndarray) -> np.ndarray:
    h, w = mask.shape
    out = []
    for p in points:
        x = np.clip(np.round(p[:, 0]).astype(int), 0, w - 1)
        y = np.clip(np.round(p[:, 1]).astype(int), 0, h - 1)
        out.append(mask[y, x].mean() >= IN_MASK_SHARE)
    return np.array(out, dtype=bool)


def run_one(job: tuple[Path, dict[str, str], list[str], float, float]) -> dict[str, Any]:
    """One case: the statistic with the piece known (each mask) and the largest over the scanned regions."""
    import forensics_plugins.lens_distortion.consistency as consistency
    from forensics_core.evidence import load_evidence
    from forensics_plugins.lens_distortion.detector import analyse
    from forensics_plugins.lens_distortion.spec import DEFAULT_PARAMS

    suite, row, masks, tau0, radius = job
    kept: dict[str, Any] = {}
    departures = consistency._departures

    def keep_final(lines, beta, cov, noise, model_var, k1_line=None, line_var=None):
        out = departures(lines, beta, cov, noise, model_var, k1_line, line_var)
        if k1_line is not None:
            kept.update(delta=out.delta, var=out.line_var, x=-out.gradient, beta=np.asarray(beta))
        return out

    consistency._departures = keep_final
    try:
        result = analyse(load_evidence(suite / row["file"]).luma, DEFAULT_PARAMS)
    finally:
        consistency._departures = departures
    record: dict[str, Any] = {"file": row["file"], "kind": row["kind"], "known": [], "unknown": None, "hit": None}
    records = [r for r in (result.details.get("lines") or []) if r.get("informative")]
    if not kept or len(records) != len(kept["delta"]):
        return record
    points = [np.asarray(r["points_px"], dtype=float) for r in records]
    shape = result.details["image_shape"]
    scale = result.details["scale_px"]
    mid = np.array([(p.mean(axis=0) - [(shape[1] - 1) / 2, (shape[0] - 1) / 2]) / scale for p in points])
    chord = np.array([p[-1] - p[0] for p in points])
    lines = {**kept, "mid": mid, "horizontal": np.abs(chord[:, 0]) > np.abs(chord[:, 1])}
    dof = float(DEFAULT_PARAMS["dof"])
    for m in masks:
        region = _in_mask(points, np.asarray(Image.open(suite / m).convert("L")) >= 128)
        if region.sum() >= 3 and (~region).sum() >= 6:
            record["known"].append(region_z(lines, region, tau0, dof))
    long = np.array([r["length_px"] for r in records]) >= 0.2 * min(shape)
    best, best_region = 0.0, None
    for seed in np.flatnonzero(long):
        region = np.hypot(*(mid - mid[seed]).T) <= radius
        if region.sum() >= 3 and (~region).sum() >= 6:
            z = region_z(lines, region, tau0, dof)
            if z > best:
                best, best_region = z, region
    record["unknown"] = best
    if row["mask"] and best_region is not None:
        record["hit"] = bool((_in_mask(points, np.asarray(Image.open(suite / row["mask"]).convert("L")) >= 128)
                              & best_region).any())
    return record


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", type=Path, default=DEFAULT_SUITE)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--tau0", type=float, default=0.02)
    parser.add_argument("--radius", type=float, default=0.35)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    truth = args.suite / "truth.csv"
    if not truth.is_file():
        print(f"suite absent ({args.suite}): build it with `forensics validate lens-splices` or "
              "forensics_core.validation.lens_splices")
        return
    import csv

    with truth.open(newline="") as f:
        rows = list(csv.DictReader(f))
    by_host: dict[str, list[str]] = {}
    for row in rows:
        if row["mask"]:
            by_host.setdefault(row["host"], []).append(row["mask"])
    jobs = [(args.suite, row, [row["mask"]] if row["mask"] else by_host.get(row["host"], []), args.tau0, args.radius)
            for row in rows]
    with ProcessPoolExecutor(args.workers) as pool:
        records = list(pool.map(run_one, jobs, chunksize=1))
    print(f"{args.suite}: {len(records)} cases; tau0 {args.tau0:g}, scan radius {args.radius:g}")
    print("piece known (its mask; a control at its host's splices' masks): share of measured pieces with |z| above")
    for kind in KINDS:
        z = np.array([v for r in records if r["kind"] == kind for v in r["known"]])
        if z.size:
            print(f"  {kind:13s} {z.size:3d} pieces   > 2: {np.mean(z > 2):4.0%}   > 3: {np.mean(z > 3):4.0%}   "
                  f"> 4: {np.mean(z > 4):4.0%}")
    controls = np.array([r["unknown"] for r in records if r["kind"] == "control" and r["unknown"] is not None])
    if controls.size:
        q95, q100 = np.quantile(controls, 0.95), controls.max()
        print(f"piece unknown (largest over the scanned regions): controls' 95th percentile {q95:.1f}, maximum "
              f"{q100:.1f}")
        for kind in KINDS:
            z = [r for r in records if r["kind"] == kind and r["unknown"] is not None]
            above = [r for r in z if r["unknown"] > q100]
            print(f"  {kind:13s} {len(z):3d} cases   > 95th: {np.mean([r['unknown'] > q95 for r in z]):4.0%}   "
                  f"> maximum: {len(above) / max(len(z), 1):4.0%} ({sum(bool(r['hit']) for r in above)} of them "
                  "on the piece)")
    if args.out:
        args.out.write_text(json.dumps(records, indent=1))
        print(f"per-case records: {args.out}")


if __name__ == "__main__":
    sys.exit(main())
