"""How the lens distortion detector does on real-photo splices: the ``lens-splices`` suite.

Usage: ``python benchmarks/lens_splices.py [--suite /tmp/lens_splices] [--workers 2] [--out cases.json]
[--module forensics_plugins.lens_distortion]``

The suite (built by ``forensics validate lens-splices``, see
:mod:`forensics_core.validation.lens_splices`) holds authentic building
photos with a piece pasted from another camera's photo (``other_camera``),
moved to another distance from the centre (``moved``) or rescaled
(``rescaled``), and each host untouched (``control``), all saved alike. The
detector (``analyse`` with its ``DEFAULT_PARAMS``) runs on each photo's luma
and this prints, per kind and per kind and ``two_directions`` (whether the
piece holds lines of two directions at least 30 degrees apart):

* ``n`` and the share of cases where the detector ran (status ok);
* the share with image-level p < 0.01;
* the share with a candidate region (``details["region"]``, the one that
  departs most from one lens), and the median and 90th percentile of its
  log10 Bayes factor over the cases that have one; the detector gives no
  number (None) where the region's lines run in one direction only, whose
  bound is -inf, and it is counted as such (quantiles: ``method="lower"``,
  an order statistic, which -inf cannot turn into NaN);
* the share whose strongest region has a line inside the case's mask, i.e.
  points at the pasted piece (over all cases of the row; blank for
  controls, which have no mask).

Then what the pasted lines actually do (issue 37, item 3):

* per kind, the informative lines inside the mask against those outside
  it: the share departing by more than two standard errors (``|z| > 2``)
  and the median ``|z|``;
* what each pasted line should read, from the recipe and the lens its
  source frame shows untouched (that photo's control's ``k1 +- stderr``):
  a line at signed distance ``rho`` from the centre, along its normal,
  bows by ``k1 rho s^2`` (paper eqs. 1-5, to first order), so copied with
  its pixels it reads ``k1_source (rho_s / rho_d) (R_d / R_s)^2 / c``
  (:func:`reading_ratio`; a line moved across the centre reads the
  opposite sign). Printed: the lines' ``|z|`` against that prediction and
  against the host's lens, the correlation of predicted and read
  departures, and the pieces whose mean predicted departure is measurable
  (more than twice its error and the pasted lines' combined error), with
  how many of those hold two directions and were called (p < 0.01). Those
  pieces, of the other-camera and moved kinds, are the ones issue 37's
  splice target counts; each is listed with the most its lines could give
  with the piece known (:func:`best_case_evidence`, as a likelihood ratio).

Then whether the pasted lines, taken together, read another lens than the
rest of the photo (the region against the rest, issue 37 item 3): each set
of lines gets its random-effects mean ``k1`` (DerSimonian-Laird: each
line's stated error plus the spread between lines that those errors do not
explain, estimated from the lines themselves), and ``z`` is the difference
of the two means over its combined error.

* with the pasted piece known (its mask; for a control, the masks of its
  host's splices): the share of cases with ``|z| > 3`` and the median
  between-line spread inside and outside;
* without it, as a test must: the largest ``|z|`` over the regions the
  detector's region test would weigh (the informative lines within its
  radius of a long line's midpoint, in two directions), its 90th and 95th
  percentiles over the controls, and the share of each kind above them.

Last, the most a known piece could give (:func:`best_case_evidence`): its
lines fitted by one lens about a displaced centre (three parameters, fitted
to the piece itself, so optimistic), weighed against the detector's null
with its own error model, the smaller of the two direction families' sums
as the region test requires; per kind the median, 75th percentile and
largest, and the share above the largest of the controls' (the same masks
over the untouched hosts). If this stays small, no region test can speak
on these pieces, however it searches.

``--out`` saves every case's record (status, p-value, evidence, the region,
informative lines, the global k1, which lines lie in the mask, the time
``analyse`` took). ``--module`` names another copy of the plugin, a package
with the same ``detector`` and ``spec`` modules, so that an older version can
be run on the same suite, e.g. the committed one::

    mkdir -p /tmp/baseplug/lens_base
    for f in $(git ls-tree --name-only HEAD forensics_plugins/lens_distortion/ | grep '\\.py$'); do
        git show HEAD:$f > /tmp/baseplug/lens_base/$(basename $f); done
    PYTHONPATH=/tmp/baseplug python benchmarks/lens_splices.py --module lens_base --out base.json

Without the suite folder it says how to build it and exits 0. The photos and
masks are only read.
"""

from __future__ import annotations

import argparse
import csv
import importlib
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

DEFAULT_SUITE = Path("/tmp/lens_splices")
DEFAULT_MODULE = "forensics_plugins.lens_distortion"
TRUTH_FILE = "truth.csv"
KINDS = ("other_camera", "moved", "rescaled", "control")
P_CALLED = 0.01
#: A line counts as inside the mask when at least this share of its points are.
IN_MASK_SHARE = 0.5
#: |z| of the region against the rest counted as a clear difference.
CLEAR_Z = 3.0


def cases(suite: Path) -> list[dict[str, str]]:
    """The rows of the suite's ``truth.csv``, in its order.

    Parameters
    ----------
    suite : Path
        The suite folder.

    Returns
    -------
    list of dict
        One row per photo, keyed by the CSV header (``file``, ``mask``,
        ``kind``, ``jpeg_quality``, ``resized``, ``two_directions``, ...).
    """
    with (suite / TRUTH_FILE).open(newline="") as f:
        return list(csv.DictReader(f))


def lines_in_mask(lines: list[dict[str, Any]], ids: list[int], mask: np.ndarray) -> list[int]:
    """The ids among ``ids`` of the lines that lie inside ``mask``.

    Parameters
    ----------
    lines : list of dict
        ``details["lines"]``; line ``i`` (id ``i + 1``) has ``points_px``, x and y in pixels.
    ids : list of int
        One-based line ids, as the detector reports them.
    mask : ndarray of bool, shape (H, W)
        The pasted piece.

    Returns
    -------
    list of int
        The ids of the lines with at least :data:`IN_MASK_SHARE` of their
        points in the mask. A majority rather than any point, because a host
        line running past the piece touches its border without being pasted.
    """
    h, w = mask.shape
    inside = []
    for i in ids:
        pts = np.asarray(lines[i - 1]["points_px"], dtype=float)
        x = np.clip(np.round(pts[:, 0]).astype(int), 0, w - 1)
        y = np.clip(np.round(pts[:, 1]).astype(int), 0, h - 1)
        if np.mean(mask[y, x]) >= IN_MASK_SHARE:
            inside.append(i)
    return inside


def run_one(job: tuple[str, Path, dict[str, str]]) -> dict[str, Any]:
    """Analyse one case of the suite and record what the summary and a later comparison need.

    Parameters
    ----------
    job : tuple
        The plugin package's module name, the suite folder, the case's
        ``truth.csv`` row and the masks (relative to the suite) whose lines
        are marked: its own, or for a control those of its host's splices.

    Returns
    -------
    dict
        The case's record (JSON-ready); ``status`` is ``"error: ..."`` when
        ``analyse`` raised.
    """
    from forensics_core.evidence import load_evidence

    module, suite, row, region_masks = job
    detector = importlib.import_module(f"{module}.detector")
    spec = importlib.import_module(f"{module}.spec")
    record: dict[str, Any] = {
        "file": row["file"], "kind": row["kind"], "two_directions": row["two_directions"] or None,
        "jpeg_quality": int(row["jpeg_quality"]), "resized": row["resized"],
    }
    luma = load_evidence(suite / row["file"]).luma
    t0 = time.perf_counter()
    try:
        result = detector.analyse(luma, spec.DEFAULT_PARAMS)
    except Exception as exc:  # noqa: BLE001 - one failing photo must not lose the rest of a long run
        return {**record, "status": f"error: {type(exc).__name__}: {exc}", "elapsed_s": time.perf_counter() - t0}
    elapsed = time.perf_counter() - t0
    details = result.details
    lines = details.get("lines") or []
    region = details.get("region")
    model = details.get("global_model") or {}
    if not row["mask"]:
        record["departures"] = [{"z": ln["z"], "delta_k1": ln["delta_k1"], "delta_k1_stderr": ln["delta_k1_stderr"],
                                 "in_mask": False} for ln in lines if ln.get("informative") and ln.get("z") is not None]
    record.update({
        "host": row.get("host"), "donor": row.get("donor"),
        "status": result.status.value, "p_value": result.p_value, "evidence": details.get("evidence"),
        "region": None if region is None else {
            key: region.get(key)
            for key in ("log10_bayes_factor", "alternative", "decided", "n_regions", "line_ids", "pasted_line_ids")
        },
        "n_lines": len(lines), "n_informative": sum(bool(ln.get("informative")) for ln in lines),
        "flagged_line_ids": details.get("flagged_line_ids") or [],
        "k1": model.get("k1"), "k1_stderr": model.get("k1_stderr"), "elapsed_s": elapsed,
    })
    informative = [ln for ln in lines if ln.get("informative") and ln.get("k1") is not None
                   and ln.get("k1_stderr") is not None and np.isfinite(ln["k1_stderr"])]
    masks = [np.asarray(Image.open(suite / m).convert("L")) >= 128 for m in region_masks]
    record["lines"] = []
    for ln in informative:
        (x0, y0), (x1, y1) = ln["endpoints_px"]
        record["lines"].append({
            "k1": ln["k1"], "k1_stderr": ln["k1_stderr"], "length_px": ln["length_px"],
            "mid_px": [(x0 + x1) / 2.0, (y0 + y1) / 2.0], "direction": float(np.arctan2(y1 - y0, x1 - x0)),
            "in_masks": [bool(lines_in_mask(lines, [ln["id"]], m)) for m in masks]})
    record["shape"] = list(luma.shape[:2])
    if row["mask"]:
        mask = masks[0]
        record["departures"] = [
            {"z": ln["z"], "delta_k1": ln["delta_k1"], "delta_k1_stderr": ln["delta_k1_stderr"],
             "in_mask": bool(lines_in_mask(lines, [ln["id"]], mask))}
            for ln in lines if ln.get("informative") and ln.get("z") is not None]
        region_in = lines_in_mask(lines, region["line_ids"], mask) if region else []
        flagged_in = lines_in_mask(lines, record["flagged_line_ids"], mask)
        record.update({"region_line_ids_in_mask": region_in, "flagged_line_ids_in_mask": flagged_in,
                       "region_in_mask": bool(region_in), "flagged_in_mask": bool(flagged_in)})
    return record


def _share(values: list[bool]) -> str:
    return f"{np.mean(values):6.0%}" if values else f"{'-':>6s}"


def summary_line(label: str, rows: list[dict[str, Any]]) -> str:
    """One line of the summary table over ``rows``.

    Parameters
    ----------
    label : str
        The row's name (kind, or kind and ``two_directions``).
    rows : list of dict
        Records of :func:`run_one`.

    Returns
    -------
    str
        n, the shares ok, with p < 0.01 and with a region, the region's log10
        Bayes factor (median, 90th percentile) and the share whose region has
        a line in the mask.
    """
    # None is the -inf bound of a one-direction region: no evidence, not a missing case.
    bf = [-np.inf if r["region"]["log10_bayes_factor"] is None else r["region"]["log10_bayes_factor"]
          for r in rows if r.get("region")]
    masked = [r for r in rows if "region_in_mask" in r]
    return (f"{label:26s} {len(rows):4d} {_share([r['status'] == 'ok' for r in rows])} "
            f"{_share([r.get('p_value') is not None and r['p_value'] < P_CALLED for r in rows])} "
            f"{_share([bool(r.get('region')) for r in rows])} "
            + (" ".join(f"{np.percentile(bf, q, method='lower'):+9.2f}" for q in (50, 90)) if bf
               else f"{'-':>9s} {'-':>9s}")
            + f" {_share([r['region_in_mask'] for r in masked])}")


def print_summary(records: list[dict[str, Any]]) -> None:
    """Print the table per kind, then per kind and ``two_directions``.

    Parameters
    ----------
    records : list of dict
        Records of :func:`run_one`.
    """
    print(f"{'':26s} {'n':>4s} {'ok':>6s} {'p<.01':>6s} {'region':>6s} {'BF med':>9s} {'BF p90':>9s} {'inmask':>6s}")
    for kind in KINDS:
        rows = [r for r in records if r["kind"] == kind]
        if rows:
            print(summary_line(kind, rows))
    print()
    for kind in KINDS:
        for two in ("no", "yes", None):
            rows = [r for r in records if r["kind"] == kind and r["two_directions"] == two]
            if rows:
                print(summary_line(f"{kind}, two_dir {two or '-'}", rows))
    errors = [r for r in records if r["status"].startswith("error")]
    for r in errors:
        print(f"  {r['file']}: {r['status']}")


def print_pasted_lines(records: list[dict[str, Any]], recipes: dict[str, dict[str, Any]], module: str) -> None:
    """Print what the pasted lines do: their departures, and the departure the paste should cause.

    Parameters
    ----------
    records : list of dict
        Records of :func:`run_one`.
    recipes : dict
        The suite's ``recipes.json`` cases by file name.
    """
    print("\ninformative lines inside the pasted piece against outside it: share |z| > 2, median |z|")
    for kind in KINDS:
        rows = [r for r in records if r["kind"] == kind and r["status"] == "ok"]
        for label, inside in (("inside", True), ("outside", False)):
            z = np.abs([d["z"] for r in rows for d in r.get("departures", []) if d["in_mask"] == inside])
            if z.size:
                print(f"  {kind:13s} {label:8s} {z.size:5d} lines  |z| > 2: {np.mean(z > 2):5.1%}  median "
                      f"{np.median(z):.2f}")
    lens = {r["host"]: (r["k1"], r["k1_stderr"]) for r in records
            if r["kind"] == "control" and r["status"] == "ok" and r["k1"] is not None}
    print("\nwhat each pasted line should read (its source's lens, paper eqs. 1-5 with signed distances) against what it "
          "reads;\nz of the line's k1 against that prediction, and against the host's lens (no paste)")
    for kind in KINDS[:3]:
        lines, cases_ = [], []
        for r in records:
            recipe = recipes.get(r["file"])
            if r["kind"] != kind or r["status"] != "ok" or recipe is None or r["host"] not in lens:
                continue
            source = r["donor"] if kind == "other_camera" else r["host"]
            if source not in lens:
                continue
            host, host_se = lens[r["host"]]
            src, src_se = lens[source]
            pasted = [ln for ln in r.get("lines", []) if ln["in_masks"] and ln["in_masks"][0]]
            if not pasted:
                continue
            ratio = np.array([reading_ratio(ln, recipe, r["shape"]) for ln in pasted])
            read = np.array([ln["k1"] for ln in pasted])
            se = np.array([ln["k1_stderr"] for ln in pasted])
            z_paste = (read - src * ratio) / np.hypot(se, src_se * ratio)
            z_host = (read - host) / np.hypot(se, host_se)
            lines.append(np.column_stack((z_paste, z_host, src * ratio - host, read - host)))
            w = se**-2.0
            mean_pred = float(w @ (src * ratio - host) / w.sum())
            pred_se = float(np.hypot(np.sqrt(w @ (src_se * ratio) ** 2) / np.sqrt(w.sum()) if w.sum() else 0, host_se))
            cases_.append((abs(mean_pred) > 2.0 * max(pred_se, float(w.sum() ** -0.5)), r))
        if not lines:
            continue
        a = np.vstack(lines)
        measurable = [r for m, r in cases_ if m]
        both = [r for r in measurable if r["two_directions"] == "yes"]
        called = [r for r in both if r["p_value"] is not None and r["p_value"] < P_CALLED]
        print(f"  {kind:13s} {len(a):4d} lines of {len(cases_)} pieces: |z| median {np.median(np.abs(a[:, 0])):.2f} against the "
              f"prediction, {np.median(np.abs(a[:, 1])):.2f} against the host; within 2: {np.mean(np.abs(a[:, 0]) < 2):.0%} and "
              f"{np.mean(np.abs(a[:, 1]) < 2):.0%}; correlation of predicted and read departures "
              f"{np.corrcoef(a[:, 2], a[:, 3])[0, 1]:+.2f}; pieces whose mean predicted departure is measurable "
              f"{len(measurable)}, of them in two directions {len(both)}, called {len(called)}")
        # Issue 37's splice target counts exactly these pieces (cross-camera and moved): what could they give at best?
        for r in both:
            best = best_case_evidence(r, np.array([ln["in_masks"][0] for ln in r["lines"]]), module)
            shown = "fewer than four structures or one family" if best is None else f"LR {math.exp(best):.1f}"
            print(f"      {r['file']}: p {r['p_value']:.2g}; at best, with the piece known: {shown}")


def reading_ratio(line: dict[str, Any], recipe: dict[str, Any], shape: list[int]) -> float:
    """What a pasted line reads, as a multiple of its source frame's ``k1``.

    A line at signed distance ``rho`` from the centre (along its normal) is
    displaced by ``k1 rho s^2`` at abscissa ``s`` beyond what a straight line
    absorbs (normalised units; paper eqs. 1-5 to first order). Copied with
    its pixels, scaled by ``c``, from a frame of half-size ``R_s`` to one of
    half-size ``R_d``, it reads ``k1_source (rho_s / rho_d) (R_d / R_s)^2 / c``.
    The sign matters: a line moved across the centre reads the opposite sign.

    Parameters
    ----------
    line : dict
        A record's line: ``mid_px`` (x, y) in the exported photo and ``direction`` (radians).
    recipe : dict
        The case's recipe: ``source`` and ``destination`` boxes (x, y, w, h), ``scale``, the host's
        ``size``, the donor's ``resized_to`` and the export's ``size`` (all (w, h) pixels).
    shape : list of int
        The exported photo's (H, W).

    Returns
    -------
    float
    """
    host_w, host_h = recipe["host"]["size"]
    export_w, export_h = recipe["export"]["size"]
    mid = (np.asarray(line["mid_px"], dtype=float) + 0.5) * [host_w / export_w, host_h / export_h] - 0.5
    normal = np.array([-np.sin(line["direction"]), np.cos(line["direction"])])
    c = recipe.get("scale") or 1.0
    frame = recipe["donor"]["resized_to"] if recipe.get("donor") else [host_w, host_h]
    source_mid = (mid - recipe["destination"][:2]) / c + recipe["source"][:2]
    rho_d = normal @ (mid - [(host_w - 1) / 2, (host_h - 1) / 2])
    rho_s = normal @ (source_mid - [(frame[0] - 1) / 2, (frame[1] - 1) / 2])
    rho_d = rho_d if abs(rho_d) > 1e-6 else 1e-6
    return float(rho_s / rho_d * (max(host_w, host_h) / max(frame)) ** 2 / c)


def random_effects_mean(k1: np.ndarray, stderr: np.ndarray) -> tuple[float, float, float]:
    """DerSimonian-Laird random-effects mean of lines' ``k1``: the mean, its standard error and the spread.

    Parameters
    ----------
    k1, stderr : ndarray, shape (n,), n >= 2
        Each line's ``k1`` and its stated standard error.

    Returns
    -------
    tuple of float
        The mean, its standard error, and ``tau``, the between-line standard
        deviation the stated errors do not explain (moment estimate).

    References
    ----------
    .. [1] R. DerSimonian, N. Laird, Meta-analysis in clinical trials,
       Controlled Clinical Trials 7(3), 1986.
    """
    w = stderr**-2.0
    mean = np.sum(w * k1) / w.sum()
    q = np.sum(w * (k1 - mean) ** 2)
    tau2 = max(0.0, (q - (k1.size - 1)) / (w.sum() - np.sum(w**2) / w.sum()))
    w = 1.0 / (stderr**2 + tau2)
    return float(np.sum(w * k1) / w.sum()), float(w.sum() ** -0.5), float(np.sqrt(tau2))


def _against_rest(lines: list[dict[str, Any]], inside: np.ndarray) -> tuple[float, float, float] | None:
    """``z`` of the lines ``inside`` against the others, and each side's spread; None with under 2 a side."""
    if inside.sum() < 2 or (~inside).sum() < 2:
        return None
    k = np.array([ln["k1"] for ln in lines])
    s = np.array([ln["k1_stderr"] for ln in lines])
    a, b = random_effects_mean(k[inside], s[inside]), random_effects_mean(k[~inside], s[~inside])
    return (a[0] - b[0]) / np.hypot(a[1], b[1]), a[2], b[2]


def best_region_z(record: dict[str, Any]) -> float | None:
    """The largest ``|z|`` of a region against the rest over the regions the region test weighs."""
    from forensics_plugins.lens_distortion.regions import FAMILY_DEG, REGION_MIN_LENGTH, REGION_RADIUS

    lines = record.get("lines") or []
    if len(lines) < 4:
        return None
    h, w = record["shape"]
    scale = max(h, w) / 2.0
    mid = np.array([ln["mid_px"] for ln in lines]) / scale
    direction = np.array([ln["direction"] for ln in lines])
    long_enough = np.array([ln["length_px"] for ln in lines]) >= REGION_MIN_LENGTH * min(h, w)
    best = None
    for seed in np.flatnonzero(long_enough):
        inside = long_enough & (np.hypot(*(mid - mid[seed]).T) <= REGION_RADIUS)
        turn = np.abs((direction[inside] - direction[seed] + np.pi / 2) % np.pi - np.pi / 2)
        if not (np.any(turn < np.radians(FAMILY_DEG)) and np.any(turn >= np.radians(FAMILY_DEG))):
            continue
        found = _against_rest(lines, inside)
        if found is not None and (best is None or abs(found[0]) > best):
            best = abs(found[0])
    return best


def print_region_against_rest(records: list[dict[str, Any]]) -> None:
    """Print whether pasted lines read another lens than the rest of the photo (module docstring).

    Parameters
    ----------
    records : list of dict
        Records of :func:`run_one`.
    """
    ok = [r for r in records if r["status"] == "ok" and r.get("lines")]
    print(f"\nthe region against the rest (random-effects mean k1 of each side; |z| > {CLEAR_Z:g} counted)")
    for kind in KINDS:
        found = [x for r in ok if r["kind"] == kind
                 for i in range(len(r["lines"][0]["in_masks"]))
                 if (x := _against_rest(r["lines"], np.array([ln["in_masks"][i] for ln in r["lines"]])))]
        if found:
            z = np.abs([x[0] for x in found])
            print(f"  piece known   {kind:13s} {len(z):3d} pieces  |z| > {CLEAR_Z:g}: {np.mean(z > CLEAR_Z):4.0%}  "
                  f"spread of lines' k1, median: inside {np.median([x[1] for x in found]):.3f}, outside "
                  f"{np.median([x[2] for x in found]):.3f}")
    best = {kind: [z for r in ok if r["kind"] == kind if (z := best_region_z(r)) is not None] for kind in KINDS}
    if len(best["control"]) < 10:
        return
    for q in (0.90, 0.95):
        threshold = float(np.quantile(best["control"], q))
        shares = ", ".join(f"{kind} {np.mean(np.array(v) > threshold):.0%} of {len(v)}" for kind, v in best.items()
                           if v)
        print(f"  piece unknown best region |z| above the controls' {q:.0%} point ({threshold:.1f}): {shares}")


def best_case_evidence(record: dict[str, Any], inside: np.ndarray, module: str) -> float | None:
    """The most evidence a known piece's lines can give for a paste, with the region test's own error model.

    The piece's informative lines are grouped into structures as the
    region test groups them (``regions.structures``) and split into two
    direction families (``regions.FAMILY_DEG``). The alternative is the
    widest the paper allows: the piece follows one lens about a displaced
    centre, so a structure at signed distance ``rho`` with unit normal ``n``
    reads ``a + b . n / rho`` (``a`` the lens's ``k1``, ``b`` its centre's
    displacement times ``-a``; eqs. 1-5 to first order), fitted by weighted
    least squares to the piece itself, so the figure is optimistic. Each
    structure's log-likelihood ratio is that fit's Gaussian (its standard
    error and 10 % of the reading) against the null's Student t
    (``error_model.DOF``) of its departure from the photo's lens as the
    detector states it (``departures``); the smaller of the two
    families' sums is returned, as the region test requires both to carry
    the evidence. None when the piece holds fewer than four structures or
    one family only.

    Parameters
    ----------
    record : dict
        A record of :func:`run_one` (its ``lines``, ``departures``, ``k1`` and ``shape``).
    inside : ndarray of bool, shape (n_lines,)
        Which of the record's lines lie in the piece.
    module : str
        The plugin package whose ``regions`` and ``error_model`` are used.

    Returns
    -------
    float or None
        Natural-log likelihood ratio.
    """
    regions = importlib.import_module(f"{module}.regions")
    dof = importlib.import_module(f"{module}.error_model").DOF
    kept = [(ln, d) for ln, d, keep in zip(record["lines"], record["departures"], inside) if keep]
    if len(kept) < 4 or record.get("k1") is None:
        return None
    lines = [ln for ln, _ in kept]
    h, w = record["shape"]
    scale = max(h, w) / 2.0
    mid = (np.array([ln["mid_px"] for ln in lines]) - [(w - 1) / 2.0, (h - 1) / 2.0]) / scale
    direction = np.array([ln["direction"] for ln in lines])
    # Departures from the photo's lens as the detector states them (k2 and the centre included), and what the
    # lines read about the image centre with the photo's k1 added back.
    departure = np.array([d["delta_k1"] for _, d in kept])
    se = np.array([d["delta_k1_stderr"] for _, d in kept])
    reading = record["k1"] + departure
    groups = regions.structures(mid, direction, np.arange(len(lines)))
    if len(groups) < 4:
        return None
    rep = np.array([g[np.argmin(se[g])] for g in groups])
    y = np.array([se[g] ** -2.0 @ reading[g] / np.sum(se[g] ** -2.0) for g in groups])
    s = se[rep]
    turn = np.abs((direction[rep] - direction[rep[0]] + np.pi / 2) % np.pi - np.pi / 2)
    family = turn < np.radians(regions.FAMILY_DEG)
    if family.all() or not family.any():
        return None
    normal = np.column_stack((-np.sin(direction[rep]), np.cos(direction[rep])))
    rho = np.einsum("ij,ij->i", mid[rep], normal)
    rho = np.where(np.abs(rho) < 1e-3, np.copysign(1e-3, rho), rho)
    design = np.column_stack((np.ones(len(rep)), normal / rho[:, None]))
    beta = np.linalg.lstsq(design / s[:, None], y / s, rcond=None)[0]
    fitted = design @ beta
    delta = np.array([se[g] ** -2.0 @ departure[g] / np.sum(se[g] ** -2.0) for g in groups])
    llr = (regions._log_normal(y - fitted, np.hypot(s, 0.1 * fitted)) - regions._log_t(delta, s, dof))
    return float(min(llr[family].sum(), llr[~family].sum()))


def print_best_case(records: list[dict[str, Any]], module: str) -> None:
    """Print, per kind, the evidence known pieces could give at best (:func:`best_case_evidence`).

    For a control, the pieces are its host's splices' masks over the untouched photo.
    """
    ok = [r for r in records if r["status"] == "ok" and r.get("lines")]
    values = {kind: [x for r in ok if r["kind"] == kind for i in range(len(r["lines"][0]["in_masks"]))
                     if (x := best_case_evidence(r, np.array([ln["in_masks"][i] for ln in r["lines"]]), module))
                     is not None] for kind in KINDS}
    print("\nat best, with the piece known: its lines fitted by one lens about a displaced centre, the smaller "
          "of its two direction families' log-likelihood ratios against the photo's lens")
    top = max(values["control"], default=np.nan)
    for kind, v in values.items():
        if v:
            print(f"  {kind:13s} {len(v):3d} pieces in two directions: median {np.median(v):5.1f}, 75 % "
                  f"{np.quantile(v, 0.75):5.1f}, largest {max(v):5.1f}; above the controls' largest: "
                  f"{np.mean(np.array(v) > top):.0%}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", type=Path, default=DEFAULT_SUITE)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, help="JSON file for the per-case records")
    parser.add_argument("--module", default=DEFAULT_MODULE,
                        help="package whose .detector.analyse and .spec.DEFAULT_PARAMS are run")
    args = parser.parse_args()
    if not (args.suite / TRUTH_FILE).exists():
        print(f"suite absent ({args.suite}): build it with `forensics validate lens-splices` or "
              f"forensics_core.validation.lens_splices")
        sys.exit(0)
    # Imported here too so that a wrong --module fails at once, not in every worker.
    spec = importlib.import_module(f"{args.module}.spec")
    importlib.import_module(f"{args.module}.detector")
    rows = cases(args.suite)
    host_masks: dict[str, list[str]] = {}
    for row in rows:
        if row["mask"]:
            host_masks.setdefault(row.get("host", ""), []).append(row["mask"])
    jobs = [(args.module, args.suite, row, [row["mask"]] if row["mask"] else host_masks.get(row.get("host", ""), []))
            for row in rows]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        records = list(pool.map(run_one, jobs))
    wall = time.perf_counter() - t0
    print(f"{args.module} ({spec.__file__}), version {getattr(spec, 'VERSION', '?')}: {len(records)} cases "
          f"from {args.suite} in {wall:.0f} s on {args.workers} workers")
    print_summary(records)
    recipes_file = args.suite / "recipes.json"
    if recipes_file.exists():
        recipes = {c["file"]: c for c in json.loads(recipes_file.read_text())["cases"]}
        print_pasted_lines(records, recipes, args.module)
    print_region_against_rest(records)
    print_best_case(records, args.module)
    if args.out is not None:
        args.out.write_text(json.dumps({"suite": str(args.suite), "module": args.module,
                                        "module_file": spec.__file__, "version": getattr(spec, "VERSION", None),
                                        "params": spec.DEFAULT_PARAMS, "wall_s": wall, "cases": records}, indent=1))
        print(f"per-case records: {args.out}")


if __name__ == "__main__":
    main()
