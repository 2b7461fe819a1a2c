"""The JPEG grid detector: from a photo to a typed result.

Stages: the luminance as decoded (:mod:`.luminance`), zero counts of the
8x8 DCT at every pixel position (:mod:`.zeros`), per-pixel votes for a grid
origin (:mod:`.votes`), the main grid's a-contrario test and the regions
voting for another grid (:mod:`.regions`, :mod:`.nfa`).

Two vote maps are used. The first is ZERO's (Nikoukhah et al., CVPRW 2019):
zeros counted as ``|c| < 0.5``, every pixel votes among the 64 origins; it
gives the main grid, the regions whose own grid shows through ("foreign")
and those where the main grid is missing ("missing"), as in a forgery saved
without recompression or at a very high quality. The second (this
implementation's extension, "hidden") excludes the main grid from the vote
and counts zeros with a looser threshold: when the whole photo was saved
again after the splice, the main grid wins every vote, but a pasted region
still holds more near-zeros on the grid of its first compression than on any
other.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from forensics_core import DetectorResult, DetectorSpec, Evidence, Status

from .luminance import MIN_SIDE, Luminance, luminance
from .nfa import finite_log10, log10_binomial_tail, nfa_text
from .regions import Region, grow_regions, mirror_references
from .votes import cell_tally, clipped_neighbourhood, grid_code, grid_origin, vote_map
from .zeros import zero_counts

NAME = "jpeg_grid"
VERSION = "1.0.0"

REFERENCES = (
    "T. Nikoukhah, J. Anger, T. Ehret, M. Colom, J.-M. Morel, R. Grompone von Gioi, JPEG Grid Detection based on "
    "the Number of DCT Zeros and its Application to Automatic and Localized Forgery Detection, IEEE/CVF CVPR "
    "Workshops, 2019, pp. 110-118.",
    "T. Nikoukhah, J. Anger, M. Colom, J.-M. Morel, R. Grompone von Gioi, ZERO: a Local JPEG Grid Origin Detector "
    "Based on the Number of DCT Zeros and its Applications in Image Forensics, Image Processing On Line 11 (2021), "
    "pp. 396-433, doi:10.5201/ipol.2021.390.",
    "A. Desolneux, L. Moisan, J.-M. Morel, From Gestalt Theory to Image Analysis: A Probabilistic Approach, "
    "Springer, 2008.",
)

DEFAULT_PARAMS: dict[str, Any] = {
    "zero_threshold": 0.5,
    "hidden_threshold": 1.5,
    "hidden_grids": True,
    "cell": 8,
    "pixels_per_trial": 64,
    "seed_windows": [11, 23],
    "grow_window": 7,
    "seed_log10": -4.0,
    "grow_fraction": 0.25,
    "min_region_tiles": 16,
    "ring_tiles": 8,
    "axis_factor": 2.0,
    "nfa_threshold": 1.0,
    "map_max_side": 96,
    "max_regions_listed": 8,
}

SPEC = DetectorSpec(
    name=NAME,
    version=VERSION,
    description="Finds the photo's 8x8 JPEG block grid from the zeros of the DCT and the regions whose grid is "
                "shifted or missing.",
    references=REFERENCES,
    default_params=DEFAULT_PARAMS,
)

# The example luminance table of the JPEG standard (ITU-T T.81, Annex K.1),
# natural order, which the IJG library scales by its quality setting.
_IJG_LUMINANCE = np.array([
    16, 11, 10, 16, 24, 40, 51, 61, 12, 12, 14, 19, 26, 58, 60, 55, 14, 13, 16, 24, 40, 57, 69, 56,
    14, 17, 22, 29, 51, 87, 80, 62, 18, 22, 37, 56, 68, 109, 103, 77, 24, 35, 55, 64, 81, 104, 113, 92,
    49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99], dtype=np.float64)


def _timed(marks: dict[str, float], stage: str, since: float) -> float:
    now = time.perf_counter()
    marks[stage] = round(now - since, 4)
    return now


def ijg_quality(table: np.ndarray | None) -> int | None:
    """The IJG quality (1-100) whose scaled standard luminance table is closest to ``table``, or None.

    A camera or editor with its own tables gets the nearest equivalent; it
    only sizes the report's wording, never the decision.
    """
    if table is None:
        return None
    q = np.arange(1, 101)[:, None]
    scale = np.where(q < 50, 5000.0 / q, 200.0 - 2.0 * q)
    tables = np.clip(np.floor((_IJG_LUMINANCE[None, :] * scale + 50.0) / 100.0), 1, 255)
    err = np.abs(np.log(tables) - np.log(np.clip(table.ravel(), 1, None))[None, :]).mean(axis=1)
    return int(np.argmin(err) + 1)


def _rle(mask: np.ndarray) -> list[list[int]]:
    """Runs ``[row, first column, length]`` of True tiles, row by row."""
    runs = []
    padded = np.pad(mask.astype(np.int8), ((0, 0), (1, 1)))
    edges = np.diff(padded, axis=1)
    for row, col in zip(*np.nonzero(edges == 1)):
        end = np.argmax(edges[row, col:] == -1) + col
        runs.append([int(row), int(col), int(end - col)])
    return runs


def _coarse_share(hist: np.ndarray, eligible: np.ndarray, grid: int, max_side: int) -> tuple[int, list[list[int]]]:
    """Share (percent) of votes for ``grid`` on blocks of tiles, at most ``max_side`` blocks on the long side."""
    ht, wt = eligible.shape
    f = max(1, int(np.ceil(max(ht, wt) / max_side)))
    hb, wb = -(-ht // f), -(-wt // f)
    pad = ((0, hb * f - ht), (0, wb * f - wt))
    votes = np.pad(hist[..., grid].astype(np.float64), pad).reshape(hb, f, wb, f).sum(axis=(1, 3))
    n = np.pad(eligible.astype(np.float64), pad).reshape(hb, f, wb, f).sum(axis=(1, 3))
    share = np.where(n > 0, np.round(100.0 * votes / np.maximum(n, 1.0)), -1).astype(int)
    return f, share.tolist()


def _region_record(i: int, region: Region, stage: str, cell: int, shape: tuple[int, int],
                   nfa_threshold: float) -> dict[str, Any]:
    rows, cols = np.nonzero(region.tiles)
    dx, dy = grid_origin(region.grid)
    log10_nfa = finite_log10(region.log10_nfa)
    return {
        "id": i,
        "stage": stage,
        "grid": [dx, dy],
        "bbox_px": [int(cols.min() * cell), int(rows.min() * cell),
                    int(min(shape[1], (cols.max() + 1) * cell)), int(min(shape[0], (rows.max() + 1) * cell))],
        "area_px": int(region.tiles.sum() * cell * cell),
        "area_fraction": round(float(region.tiles.sum() * cell * cell / (shape[0] * shape[1])), 4),
        "eligible_px": region.n_pixels,
        "votes": region.votes,
        "density": round(region.votes / max(region.n_pixels, 1), 4),
        "p_null": round(region.p_null, 6),
        "log10_nfa": round(log10_nfa, 2),
        "meaningful": bool(log10_nfa < np.log10(nfa_threshold)),
        "tiles_rle": _rle(region.tiles),
    }


def _dedupe(regions: list[tuple[str, Region]]) -> list[tuple[str, Region]]:
    """Keep, of regions that overlap, the most meaningful one.

    The two vote maps often find the same region; and inside a pasted region
    the grids sharing a row or column phase with its own grid collect votes
    too, as the main grid's neighbours do elsewhere. A region overlapping a
    stronger one by half its tiles or more is the same place and is dropped.
    """
    kept: list[tuple[str, Region]] = []
    for stage, region in sorted(regions, key=lambda sr: sr[1].log10_nfa):
        size = region.tiles.sum()
        if not any((r.tiles & region.tiles).sum() >= 0.5 * min(size, r.tiles.sum()) for _, r in kept):
            kept.append((stage, region))
    return kept


def _summary(details: dict[str, Any]) -> str:
    main = details["main_grid"]
    dx, dy = main["origin"]
    if not main["significant"]:
        return (f"Inconclusive: no JPEG block grid is significant (best origin ({dx}, {dy}), NFA "
                f"{nfa_text(main['log10_nfa'])}); the photo was never JPEG-compressed, or resizing or filtering erased "
                f"its grid, so this detector cannot speak for or against a splice.")
    crop = (" The main grid is not at (0, 0): the photo was probably cropped after compression."
            if details["cropped"] else "")
    hits = [r for r in details["regions"] if r["meaningful"]]
    lead = f"Main JPEG grid at origin ({dx}, {dy}) (NFA {nfa_text(main['log10_nfa'])})"
    if not hits:
        best = details["regions"][0]["log10_nfa"] if details["regions"] else None
        tail = "" if best is None else f" (strongest candidate NFA {nfa_text(best)})"
        return f"{lead}; no region votes significantly for another grid{tail}.{crop}"
    r = hits[0]
    more = f" and {len(hits) - 1} more" if len(hits) > 1 else ""
    where = (f"a region of {100 * r['area_fraction']:.0f}% of the photo at x {r['bbox_px'][0]}-{r['bbox_px'][2]}, "
             f"y {r['bbox_px'][1]}-{r['bbox_px'][3]}")
    if r["stage"] == "missing":
        return (f"{lead}; the main grid is missing from {where} (NFA {nfa_text(r['log10_nfa'])}){more}: its pixels "
                f"were not compressed with the rest of the photo, as a piece pasted from an uncompressed source "
                f"is.{crop}")
    return (f"{lead}; {where} votes for the grid at ({r['grid'][0]}, {r['grid'][1]}) (NFA "
            f"{nfa_text(r['log10_nfa'])}){more}: its pixels were compressed on another grid, as a pasted piece "
            f"is.{crop}")


def analyse_luminance(lum: Luminance, params: Mapping[str, Any]) -> DetectorResult:
    """Run the detector on a prepared luminance.

    Parameters
    ----------
    lum : Luminance
        From :func:`.luminance.luminance`.
    params : mapping
        :data:`DEFAULT_PARAMS` with the user's overrides.

    Returns
    -------
    DetectorResult
        ``ok`` with ``nfa`` = the smallest region NFA (or the most meaningful
        non-detection) and ``score = 1 - min(1, nfa)`` when the main grid is
        significant; ``inconclusive`` otherwise.
    """
    marks: dict[str, float] = {}
    shape = lum.y.shape
    cell = int(params["cell"])
    ppt = float(params["pixels_per_trial"])
    nfa_threshold = float(params["nfa_threshold"])
    base = {
        "image_shape": list(shape),
        "luminance": {"source": lum.source, "note": lum.note},
        "jpeg_quality_estimate": ijg_quality(lum.table),
        "thresholds": {"zero": float(params["zero_threshold"]), "hidden_zero": float(params["hidden_threshold"]),
                       "nfa": nfa_threshold, "pixels_per_trial": ppt},
    }
    if min(shape) < MIN_SIDE:
        return DetectorResult(Status.INCONCLUSIVE,
                              f"Inconclusive: the photo ({shape[1]}x{shape[0]} pixels) is too small to hold a "
                              f"measurable JPEG grid (at least {MIN_SIDE} pixels a side).",
                              details={**base, "elapsed_s": marks})
    t = time.perf_counter()
    z_std, z_hid = zero_counts(lum.y, (float(params["zero_threshold"]), float(params["hidden_threshold"])))
    t = _timed(marks, "zeros", t)
    void = clipped_neighbourhood(lum.y)
    hist, eligible = cell_tally(vote_map(z_std, void=void), cell)
    t = _timed(marks, "votes", t)

    n_eligible = float(eligible.sum())
    totals = hist.sum(axis=(0, 1), dtype=np.int64)
    order = np.argsort(-totals, kind="stable")
    main = int(order[0])
    main_log10_nfa = np.log10(64.0) + log10_binomial_tail(n_eligible / ppt, totals[main] / ppt, 1.0 / 64.0)
    significant = bool(main_log10_nfa < np.log10(nfa_threshold))
    shares = (totals / max(n_eligible, 1.0)).round(5)
    ht, wt = eligible.shape
    tile_factor, main_share = _coarse_share(hist, eligible, main, int(params["map_max_side"]))
    details: dict[str, Any] = {
        **base,
        "main_grid": {
            "origin": list(grid_origin(main)),
            "votes": int(totals[main]),
            "eligible_px": int(n_eligible),
            "share": float(shares[main]),
            "runner_up": {"origin": list(grid_origin(int(order[1]))), "share": float(shares[order[1]])},
            "log10_nfa": round(float(finite_log10(main_log10_nfa)), 2),
            "significant": significant,
            "test": "votes for the most voted origin against B(n, 1/64), n = eligible pixels / pixels_per_trial, "
                    "times 64 origins",
        },
        "vote_shares": shares.reshape(8, 8).tolist(),
        "cropped": bool(significant and main != grid_code(0, 0)),
        "regions": [],
        "map": {"cell_px": cell, "tiles_shape": [ht, wt], "block_tiles": tile_factor, "main_share_percent": main_share},
    }
    if not significant:
        details["elapsed_s"] = marks
        return DetectorResult(Status.INCONCLUSIVE, _summary(details), details=details)

    # Candidates: 63 other origins on each vote map, and the main grid's absence, per tile.
    n_maps = 2 if params["hidden_grids"] else 1
    log10_n_tests = float(np.log10((n_maps * 63 + 1) * ht * wt))
    others = [g for g in range(64) if g != main]
    found = [("foreign", r) for r in grow_regions(hist, eligible, others, {g: 1.0 / 64.0 for g in others},
                                                 log10_n_tests, params, use_ring=False)]
    # Missing grid: among the votes cast in the region, the main grid is no longer the majority. Texture
    # alone lowers the main grid's share (fewer zeros on busy blocks) but was not seen to take it below
    # three quarters; pasted pixels never compressed on it vote at random.
    cast = hist.sum(axis=-1, dtype=np.int64)
    off_main = 1.0 - float(totals[main]) / max(float(cast.sum()), 1.0)
    absent = (cast - hist[..., main])[..., None]
    found += [("missing", replace(r, grid=main)) for r in
              grow_regions(absent, cast, [0], {0: max(off_main, 0.5)}, log10_n_tests, params, use_ring=True)]
    t = _timed(marks, "foreign_regions", t)
    if params["hidden_grids"]:
        hist_h, _ = cell_tally(vote_map(z_hid, excluded=main, void=void), cell)
        rates = hist_h.sum(axis=(0, 1), dtype=np.int64) / max(n_eligible, 1.0)
        p_null = {g: float(rates[g]) for g in others}
        found += [("hidden", r) for r in grow_regions(hist_h, eligible, others, p_null, log10_n_tests, params,
                                                      use_ring=True,
                                                      references=mirror_references(main, params["axis_factor"]))]
        t = _timed(marks, "hidden_regions", t)
    regions = _dedupe(found)
    meaningful = [sr for sr in regions if sr[1].log10_nfa < np.log10(nfa_threshold)]
    # Without a detection, the strongest candidate is kept to show how far it was from one.
    regions = meaningful[: int(params["max_regions_listed"])] if meaningful else regions[:1]
    records = [_region_record(i + 1, r, stage, cell, shape, nfa_threshold) for i, (stage, r) in enumerate(regions)]
    details.update({"regions": records, "log10_n_tests": round(log10_n_tests, 3), "vote_maps": n_maps})
    _timed(marks, "report_data", t)
    details["elapsed_s"] = marks
    best = records[0]["log10_nfa"] if records else None
    nfa = 1.0 if best is None else float(min(1.0, 10.0 ** best))
    return DetectorResult(status=Status.OK, summary=_summary(details), score=1.0 - nfa, nfa=nfa, details=details)


def analyse(evidence: Evidence, params: Mapping[str, Any]) -> DetectorResult:
    """Run the detector on a piece of evidence (see :func:`analyse_luminance`)."""
    t = time.perf_counter()
    lum = luminance(evidence)
    elapsed = time.perf_counter() - t
    result = analyse_luminance(lum, params)
    result.details["elapsed_s"] = {"luminance": round(elapsed, 4), **result.details.get("elapsed_s", {})}
    return result
