"""The JPEG grid detector: from a photo to a typed result.

The method is ZERO (Nikoukhah et al., CVPRW 2019; IPOL 2021), as published:
zero counts of the 8x8 DCT at every pixel position (:mod:`.zeros`), per-pixel
votes for a grid origin (:mod:`.votes`), the most voted origin as the main
grid with its a-contrario test, then regions grown among the pixels voting
for another grid ("foreign": a piece compressed on its own grid). Without a
main grid the foreign search covers all 64 grids, so a JPEG piece pasted into
a never-compressed image is still found.

Where the main grid is missing ("missing": a piece never compressed with the
rest), ZERO compresses the photo again at quality 99 and looks for regions
voting for the new grid. Its null fails on real photos: on authentic camera
JPEGs of high quality the main grid holds only a fifth of the votes, and the
new compression takes over whole textured areas (NFA down to 1e-600; with
ZERO's own code on 9 of the first 58 MICC-F220 originals). It stays available
(``missing_method="zero_q99"``, lossless files only). By default the absence
is read on the quantisation lattice itself (:mod:`.lattice`): an untouched
block's DCT coefficients on the main grid sit on multiples of the
compression's steps, whatever the texture or the camera's quality, and a
piece that never went through that compression does not. In a JPEG file the
same reading finds the lattice of a compression before the file's own
(aligned double compression), and a piece compressed only once.

In a JPEG file the grid (0, 0) is never searched as a foreign grid:
authentic photos cropped off-grid and saved again at quality 98 keep the old
grid as main grid, and the file's own grid then forms "foreign" regions over
much of the frame.

Foreign regions that processing of the whole photo explains are published
as that processing (``details["processing"]``), not as evidence: a first
grid found all over the frame besides the main one, as a crop after a first
compression leaves (:mod:`.earlier_grid`), and first grids shifted along
each radius by one profile, as a lens correction leaves (:mod:`.resampling`);
without such a profile, a region whose grid is the first moved one pixel
along its own radius is possible processing (:func:`.resampling.radial_steps`).
Regions none of these explains stay foreign.
"""

from __future__ import annotations

import contextlib
import io
import time
from collections.abc import Callable, Iterable, Mapping
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np
from PIL import Image
from scipy import ndimage

from forensics_core import (
    PROCESSING_KEY,
    RADIAL_RESAMPLING_KEY,
    Detector,
    DetectorFinding,
    DetectorResult,
    Evidence,
    Processing,
    RadialResampling,
    Status,
)

from .earlier_grid import CELLS, LEAD, MIN_CELL_SHARE, MIN_CELL_SHARE_ALL, EarlierGrid, earlier_grid
from .lattice import FREQUENCIES, MIN_FREQUENCIES, block_any, block_coefficients, estimate_steps, missing_regions, \
    off_lattice
from .luminance import MIN_SIDE, Luminance, luminance
from .nfa import finite_log10, log10_binomial_tail, nfa_text
from .regions import P_VOTE, W, Region, find_regions, log10_n_tests, min_region_pixels
from .resampling import MIN_FIELD_SHARE, MIN_REGIONS, MIN_SPREAD_DEG, PERP_TOL, PROFILE_REL, PROFILE_TOL, RadialWarp, \
    field_explained, radial_steps, radial_warp
from .votes import grid_code, grid_origin, vote_map
from .zeros import ZERO_THRESHOLD, flat_blocks, zero_counts
from .spec import SPEC

if TYPE_CHECKING:
    from forensics_core import SyntheticCase
    from forensics_core.report import ReportSection


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


def _coarse_share(votes: np.ndarray, main: int, cell: int, max_side: int) -> tuple[int, list[list[int]]]:
    """Share (percent) of the votes cast that go to ``main``, on blocks of tiles (-1: no vote cast)."""
    ht, wt = votes.shape[0] // cell, votes.shape[1] // cell
    f = max(1, int(np.ceil(max(ht, wt) / max_side)))
    side = cell * f
    hb, wb = -(-ht // f), -(-wt // f)
    pad = ((0, hb * side - ht * cell), (0, wb * side - wt * cell))
    v = np.pad(votes[: ht * cell, : wt * cell], pad, constant_values=-1)
    for_main = (v == main).reshape(hb, side, wb, side).sum(axis=(1, 3))
    cast = (v >= 0).reshape(hb, side, wb, side).sum(axis=(1, 3))
    share = np.where(cast > 0, np.round(100.0 * for_main / np.maximum(cast, 1)), -1).astype(int)
    return f, share.tolist()


def _region_tiles(labels: np.ndarray, region: Region, cell: int) -> np.ndarray:
    """The region as 8x8 tiles: tiles holding one of its pixels, closed over one tile and filled.

    The region's pixels are its votes, scattered at about one per block; the
    closing over one tile (8 pixels, about ZERO's reach W) joins them into the
    area they cover, as ZERO's own region mask does.
    """
    x0, y0, x1, y1 = region.bbox
    ht, wt = labels.shape[0] // cell, labels.shape[1] // cell
    ty0, tx0 = y0 // cell, x0 // cell
    ty1, tx1 = min(ht, y1 // cell + 1), min(wt, x1 // cell + 1)
    crop = labels[ty0 * cell: ty1 * cell, tx0 * cell: tx1 * cell] == region.label
    small = crop.reshape(ty1 - ty0, cell, tx1 - tx0, cell).any(axis=(1, 3))
    small = ndimage.binary_closing(np.pad(small, 1), np.ones((3, 3), bool))[1:-1, 1:-1]
    tiles = np.zeros((ht, wt), bool)
    tiles[ty0:ty1, tx0:tx1] = ndimage.binary_fill_holes(small)
    return tiles


def _region_record(i: int, stage: str, region: Region, tiles: np.ndarray, cell: int, shape: tuple[int, int],
                   log10_threshold: float, explained: bool = False) -> dict[str, Any]:
    """One region as published; ``stage`` is ``"resampled"``, ``"cropped"`` or ``"radial step"`` when processing
    explains it."""
    dx, dy = grid_origin(region.grid)
    x0, y0, x1, y1 = region.bbox
    bbox_area = (x1 - x0 + 1) * (y1 - y0 + 1)
    log10_nfa = finite_log10(region.log10_nfa)
    return {
        "id": i,
        "stage": stage,
        "grid": [dx, dy],
        "bbox_px": [x0, y0, x1 + 1, y1 + 1],
        "pixels": region.n_pixels,
        "area_px": int(tiles.sum() * cell * cell),
        "area_fraction": round(float(tiles.sum() * cell * cell / (shape[0] * shape[1])), 4),
        "density": round(region.n_pixels / bbox_area, 4),
        "log10_nfa": round(float(log10_nfa), 2),
        "meaningful": bool(log10_nfa < log10_threshold and not explained),
        "tiles_rle": _rle(tiles),
    }


def _recompressed(y: np.ndarray, quality: int, decoding: Callable) -> np.ndarray:
    """The luminance compressed as a greyscale JPEG at ``quality`` and decoded, in memory."""
    buf = io.BytesIO()
    Image.fromarray(np.clip(y, 0, 255).astype(np.uint8)).save(buf, format="JPEG", quality=quality)
    with decoding(), Image.open(buf) as img:
        return np.asarray(img, dtype=np.float32)


def _lattice_stage(lum: Luminance, main: int, details: dict[str, Any], cell: int) -> list:
    """Regions off the main grid's quantisation lattice (:mod:`.lattice`), as ``(stage, region, tiles())``.

    A lossless file is read on its main grid; a JPEG file on the grid (0, 0)
    when its main grid is there too, for the lattice of a compression before
    the file's own (aligned double compression). Anything else, or no
    lattice on enough frequencies, leaves the test not applicable.
    """
    origin = grid_origin(main)
    if lum.jpeg:
        usable_source = lum.source in ("jpeg_y", "jpeg_grey") and origin == (0, 0) and lum.table is not None
        y, file_steps = lum.y, lum.table
    else:
        usable_source = lum.fine is not None
        y, file_steps = lum.fine, None
    record: dict[str, Any] = {"method": "lattice", "applicable": False, "origin": list(origin),
                              "reading": "earlier compression under the file's own" if lum.jpeg else "main grid"}
    details["lattice"] = record
    if not usable_source:
        record["reason"] = ("the file's main grid is not its own (0, 0)" if lum.jpeg
                            else "the pixels are not 8-bit")
        return []
    coef = block_coefficients(y, origin)
    hw = coef.shape[:2]
    clipped = lum.clipped if lum.clipped is not None else np.zeros(y.shape, bool)
    usable = ~block_any(clipped, origin, hw)
    lat = estimate_steps(coef, usable, file_steps)
    record.update({"steps": lat.steps.tolist(), "n_frequencies": lat.n_frequencies,
                   "on_share": round(float(np.median(lat.share[lat.steps > 0])), 3) if lat.n_frequencies else None,
                   "blocks": int(hw[0] * hw[1]), "clipped_blocks": int((~usable).sum())})
    if lat.n_frequencies < MIN_FREQUENCIES:
        record["reason"] = (f"a quantisation lattice holds on {lat.n_frequencies} of {int(FREQUENCIES.sum())} "
                            f"low frequencies (at least {MIN_FREQUENCIES} needed)")
        return []
    counts = off_lattice(coef, lat, usable)
    record.update({"applicable": True, "testable_blocks": int(counts.testable.sum()),
                   "flagged_blocks": int(counts.flagged.sum())})
    details["missing_tested"] = True
    dx, dy = origin
    found = []
    for mr in missing_regions(counts, coef[:, :, 0, 0] / 8.0 + 128.0):
        rows, cols = np.nonzero(mr.blocks)
        bbox = (dx + 8 * int(cols.min()), dy + 8 * int(rows.min()), dx + 8 * int(cols.max()) + 7,
                dy + 8 * int(rows.max()) + 7)
        region = Region(label=-1, grid=main, n_pixels=64 * mr.n_flagged, bbox=bbox, log10_nfa=mr.log10_nfa)
        found.append(("missing", region, partial(_block_tiles, mr.blocks, origin, lum.y.shape, cell)))
    return found


def _block_tiles(blocks: np.ndarray, origin: tuple[int, int], shape: tuple[int, int], cell: int) -> np.ndarray:
    """Blocks of the grid at ``origin`` as the map's tiles of ``cell`` pixels (a tile half covered or more)."""
    dx, dy = origin
    h, w = blocks.shape
    pix = np.zeros(shape, np.float32)
    pix[dy: dy + 8 * h, dx: dx + 8 * w] = np.repeat(np.repeat(blocks, 8, axis=0), 8, axis=1)
    ht, wt = shape[0] // cell, shape[1] // cell
    return pix[: ht * cell, : wt * cell].reshape(ht, cell, wt, cell).mean(axis=(1, 3)) >= 0.5


def _votes_of(y: np.ndarray) -> np.ndarray:
    return vote_map(zero_counts(y), flat_blocks(y))


def _processing_text(processing: dict[str, Any] | None) -> str:
    """The processing the grid shows, as sentences for the summary (empty when none)."""
    if not processing:
        return ""
    out = ""
    crop = processing.get("crop")
    if crop:
        dx, dy = crop["grid"]
        out += (f" The photo was cropped off the block grid (or shifted) after a first JPEG compression and saved "
                f"again: that compression's grid, at ({dx}, {dy}), leads the votes in {crop['cells_led']} of "
                f"{crop['cells']} parts of the frame, not in one place; its {crop['n_regions']} regions are that "
                f"history, not a pasted piece.")
    saved = processing.get("saved_again")
    if saved:
        out += (f" The photo was {saved['done']}: {saved['evidence']}. That is processing, not a trace of a pasted "
                f"piece.")
    step = processing.get("radial_step")
    if step:
        out += (f" {step['n_regions']} region(s) vote for the first grid moved by one pixel along their own radius, "
                f"as where a lens correction moved the pixels by about one; too few to establish the warp, they "
                f"are read as possible processing, not as a pasted piece.")
    warp = processing.get("radial")
    if warp:
        profile = warp["profile_px"]
        radii = [p["radius_px"] for p in profile]
        shifts = [abs(p["shift_px"]) for p in profile]
        out += (f" The photo was resampled by a radial warp about its centre after a first JPEG compression, as "
                f"lens correction does: {warp['n_regions']} regions at {min(radii):.0f}-{max(radii):.0f} px from "
                f"the centre vote for the first grid moved {warp['direction']} along their own radius by "
                f"{min(shifts):.0f}-{max(shifts):.0f} px. That is processing, not a pasted piece.")
    return out


def _summary(details: dict[str, Any]) -> str:
    main = details["main_grid"]
    dx, dy = main["origin"]
    hits = [r for r in details["regions"] if r["meaningful"]]
    more = f" and {len(hits) - 1} more" if len(hits) > 1 else ""
    processing = _processing_text(details.get(PROCESSING_KEY))
    if not main["significant"]:
        if not hits and processing:
            return (f"No JPEG block grid is significant over the whole photo (best origin ({dx}, {dy}), NFA "
                    f"{nfa_text(main['log10_nfa'])}), and every region voting for one is explained by "
                    f"processing.{processing}")
        if not hits:
            return (f"Inconclusive: no JPEG block grid is significant (best origin ({dx}, {dy}), NFA "
                    f"{nfa_text(main['log10_nfa'])}) and no region votes for one; the photo was never "
                    f"JPEG-compressed, or resizing or filtering erased its grid, so this detector cannot speak for or "
                    f"against a splice.")
        r = hits[0]
        return (f"No JPEG block grid is significant over the whole photo, but a region of "
                f"{100 * r['area_fraction']:.0f}% of it at x {r['bbox_px'][0]}-{r['bbox_px'][2]}, y "
                f"{r['bbox_px'][1]}-{r['bbox_px'][3]} votes for the grid at ({r['grid'][0]}, {r['grid'][1]}) (NFA "
                f"{nfa_text(r['log10_nfa'])}){more}: its pixels carry a JPEG grid the rest of the photo lacks, as a "
                f"piece of a JPEG pasted into an uncompressed image does.")
    crop = (" The main grid is not at (0, 0): the photo was probably cropped after compression."
            if details["cropped"] else "")
    crop += processing
    lead = f"Main JPEG grid at origin ({dx}, {dy}) (NFA {nfa_text(main['log10_nfa'])})"
    if not hits:
        candidates = [r for r in details["regions"] if r["stage"] not in ("resampled", "cropped", "radial step")]
        best = candidates[0]["log10_nfa"] if candidates else None
        tail = "" if best is None else f" (strongest candidate NFA {nfa_text(best)})"
        return f"{lead}; no region votes significantly for another grid{tail}.{crop}"
    r = hits[0]
    where = (f"a region of {100 * r['area_fraction']:.0f}% of the photo at x {r['bbox_px'][0]}-{r['bbox_px'][2]}, "
             f"y {r['bbox_px'][1]}-{r['bbox_px'][3]}")
    if r["stage"] == "missing":
        if details.get("lattice", {}).get("applicable"):
            history = ("the compression before the file's own" if details["lattice"]["reading"].startswith("earlier")
                       else "the main grid's compression")
            return (f"{lead}; in {where} the blocks' cosine coefficients lie off the quantisation steps of {history} "
                    f"far more often than in blocks of the same brightness and detail elsewhere (NFA "
                    f"{nfa_text(r['log10_nfa'])}){more}: that piece did not go through the compression the rest "
                    f"went through, as a piece pasted, painted or cloned off the block grid does.{crop}")
        return (f"{lead}; the main grid is missing from {where} (NFA {nfa_text(r['log10_nfa'])}){more}: once the "
                f"photo is compressed again, its pixels take the new grid where the rest keep the old one, as a piece "
                f"pasted from an uncompressed source does.{crop}")
    return (f"{lead}; {where} votes for the grid at ({r['grid'][0]}, {r['grid'][1]}) (NFA "
            f"{nfa_text(r['log10_nfa'])}){more}: its pixels were compressed on another grid, as a pasted piece "
            f"is.{crop}")


def _headline(details: dict[str, Any]) -> str:
    """The finding in one sentence for page 1: where a region departs from the main grid, or the grid alone."""
    main = details["main_grid"]
    dx, dy = main["origin"]
    hits = [r for r in details["regions"] if r["meaningful"]]
    if not hits:
        if not main["significant"]:
            if details.get(PROCESSING_KEY):
                return "No JPEG grid is significant; every region voting for one is explained by processing."
            return (f"Inconclusive: no JPEG block grid is significant (best origin ({dx}, {dy}), NFA "
                    f"{nfa_text(main['log10_nfa'])}) and no region votes for one.")
        crop = "; the photo was probably cropped after compression" if details["cropped"] else ""
        return (f"Main JPEG grid at ({dx}, {dy}) (NFA {nfa_text(main['log10_nfa'])}){crop}; no region votes "
                f"significantly for another grid.")
    r = hits[0]
    x0, y0, x1, y1 = r["bbox_px"]
    where = f"at x {x0}–{x1}, y {y0}–{y1}"
    test = f"NFA {nfa_text(r['log10_nfa'])}" + (f"; {len(hits) - 1} more region(s) too" if len(hits) > 1 else "")
    if not main["significant"]:
        return f"Region {where} carries a JPEG grid at ({r['grid'][0]}, {r['grid'][1]}) that the rest lacks ({test})."
    if r["stage"] == "missing":
        return f"Region {where} lacks the compression of the main JPEG grid ({dx}, {dy}) ({test})."
    return f"Region {where} carries another JPEG grid, at ({r['grid'][0]}, {r['grid'][1]}) ({test})."


def _saved_again(lum: Luminance, significant: bool, details: dict[str, Any]) -> dict[str, Any] | None:
    """A compression before the file's own, when the grid shows one: its kind, sentence and evidence."""
    lattice = details.get("lattice") or {}
    if lum.jpeg and lattice.get("applicable"):
        return {"kind": "recompression",
                "done": "saved again as JPEG after an earlier JPEG compression",
                "evidence": (f"on the file's own block grid, an earlier quantisation coarser than the file's holds "
                             f"on {lattice['n_frequencies']} low frequencies (median "
                             f"{100 * lattice['on_share']:.0f} % of their coefficients on it)")}
    if not lum.jpeg and significant:
        return {"kind": "lossless storage after JPEG compression",
                "done": "stored losslessly after a JPEG compression",
                "evidence": (f"its pixels keep a JPEG block grid at {tuple(details['main_grid']['origin'])} "
                             f"(NFA {nfa_text(details['main_grid']['log10_nfa'])})")}
    return None


def _processing(warp: RadialWarp | None, n_warped: int, earlier: EarlierGrid | None, n_cropped: int,
                records: list[dict[str, Any]], saved: dict[str, Any] | None,
                n_stepped: int = 0) -> dict[str, Any] | None:
    """The processing the grid shows: what it is, the regions it explains and its evidence (None when none).

    A compression before the file's own (``saved``) is named only where no
    crop or warp is, whose descriptions already start from a first compression.
    """
    if warp is None and earlier is None and not n_stepped:
        if saved is None:
            return None
        return {**Processing(saved["kind"], saved["done"]).to_details(), "saved_again": saved}
    done = []
    out: dict[str, Any] = {}
    if n_stepped:
        done.append("possibly resampled by a radial warp about its centre after a first JPEG compression, as lens "
                     "correction does")
        out["radial_step"] = {
            "n_regions": n_stepped,
            "region_ids_listed": [r["id"] for r in records if r["stage"] == "radial step"],
            "rule": (f"with no warp established (fewer than {MIN_REGIONS} regions in directions "
                     f"{MIN_SPREAD_DEG:g} degrees apart), a region whose grid is the first grid moved by one pixel "
                     f"(0.5 to 1.5, either way) along the radius, rounded, over most of its extent, as where a "
                     f"lens correction's displacement nears one pixel; a pasted piece's grid lands there by chance "
                     f"for about 2 to 4 of the 63 other grids"),
        }
    if earlier is not None:
        done.append("cropped off the block grid after a first JPEG compression and saved again")
        out["crop"] = {
            "grid": list(grid_origin(earlier.grid)),
            "cells_led": earlier.cells_led,
            "cells": earlier.cells,
            "n_regions": n_cropped,
            "region_ids_listed": [r["id"] for r in records if r["stage"] == "cropped"],
            "rule": (f"a grid other than the main one that, its regions and their surroundings set aside, leads the "
                     f"other non-main grids' votes by {LEAD:g} times in at least {100 * MIN_CELL_SHARE:g} % of a "
                     f"{CELLS} x {CELLS} partition of the frame, or with its regions in at least "
                     f"{100 * MIN_CELL_SHARE_ALL:g} %"),
        }
    if warp is not None:
        done.append("resampled by a radial warp about its centre after a first JPEG compression, as lens "
                    "correction does")
        out[RADIAL_RESAMPLING_KEY] = {
            "direction": "outwards" if warp.at_corner_px > 0 else "inwards",
            "first_grid_origin": list(warp.origin),
            **RadialResampling(*(round(t, 2) for t in warp.terms)).to_details(),
            "n_regions": n_warped,
            "region_ids_listed": [r["id"] for r in records if r["stage"] == "resampled"],
            "shift_at_half_diagonal_px": round(warp.at_corner_px, 2),
            "profile_px": [{"radius_px": r, "shift_px": round(m, 2)} for r, m in warp.profile],
            "rule": (f"at least {MIN_REGIONS} regions in directions at least {MIN_SPREAD_DEG:g} degrees apart whose "
                     f"grids are the first grid shifted, modulo 8, along their own radius (within {PERP_TOL:g} px) "
                     f"by one radial profile D(r) = a (r / R)^3 + b (r / R), "
                     f"R the half diagonal (within {PROFILE_TOL:g} px or {100 * PROFILE_REL:g} %); once "
                     f"established, the profile refitted on the regions' pixels, and a region also explained when "
                     f"its grid is within 1 px of the shift the profile predicts at each pixel on at least "
                     f"{100 * MIN_FIELD_SHARE:g} % of its pixels"),
        }
    kind = " and ".join(k for k, x in (("crop after compression", earlier), ("radial resampling", warp),
                                        ("possible radial resampling", n_stepped)) if x)
    return {**Processing(kind, "; and ".join(done)).to_details(), **out}


def analyse_luminance(lum: Luminance, params: Mapping[str, Any],
                      decoding: Callable = contextlib.nullcontext) -> DetectorResult:
    """Run the detector on a prepared luminance.

    Parameters
    ----------
    lum : Luminance
        From :func:`.luminance.luminance`.
    params : mapping
        :data:`DEFAULT_PARAMS` with the user's overrides.
    decoding : callable
        Context manager under which Pillow decodes images made from the
        luminance (:meth:`forensics_core.Evidence.decoding`: the evidence's
        pixel limit, not Pillow's default).

    Returns
    -------
    DetectorResult
        ``ok`` when the main grid is significant (``nfa`` = the smallest
        region NFA, 1 when no region is meaningful) or, without a main grid,
        when a region votes meaningfully for a grid (``nfa`` = its NFA);
        ``score = 1 - min(1, nfa)``. ``inconclusive`` when neither.

    References
    ----------
    T. Nikoukhah, J. Anger, M. Colom, J.-M. Morel, R. Grompone von Gioi, ZERO: a Local JPEG Grid Origin Detector
    Based on the Number of DCT Zeros and its Applications in Image Forensics, IPOL 11 (2021), pp. 396-433.
    """
    marks: dict[str, float] = {}
    shape = lum.y.shape
    cell = int(params["cell"])
    log10_threshold = float(np.log10(float(params["nfa_threshold"])))
    log_nt = log10_n_tests(shape)
    base = {
        "image_shape": list(shape),
        "luminance": {"source": lum.source, "note": lum.note},
        "jpeg_quality_estimate": ijg_quality(lum.table),
        "thresholds": {"zero": ZERO_THRESHOLD, "nfa": float(params["nfa_threshold"]), "reach_px": W,
                       "recompress_quality": int(params["recompress_quality"])},
    }
    if min(shape) < MIN_SIDE:
        return DetectorResult(Status.INCONCLUSIVE,
                              f"Inconclusive: the photo ({shape[1]}x{shape[0]} pixels) is too small to hold a "
                              f"measurable JPEG grid (at least {MIN_SIDE} pixels a side).",
                              details={**base, "elapsed_s": marks},
                              headline=f"Inconclusive: the photo ({shape[1]}x{shape[0]} px) is too small for a "
                                       f"measurable JPEG grid.")
    t = time.perf_counter()
    votes = _votes_of(lum.y)
    t = _timed(marks, "votes", t)

    totals = np.bincount(votes[votes >= 0].astype(np.int64), minlength=64)
    n_cast = int(totals.sum())
    order = np.argsort(-totals, kind="stable")
    best = int(order[0])
    main_log10_nfa = log_nt + log10_binomial_tail(shape[0] * shape[1] // 64, int(totals[best]) // 64, P_VOTE)
    significant = bool(n_cast > 0 and main_log10_nfa < log10_threshold)
    main = best if significant else -1
    shares = (totals / max(n_cast, 1)).round(5)
    tile_factor, main_share = _coarse_share(votes, best, cell, int(params["map_max_side"]))
    details: dict[str, Any] = {
        **base,
        "main_grid": {
            "origin": list(grid_origin(best)),
            "votes": int(totals[best]),
            "voting_px": n_cast,
            "share": float(shares[best]),
            "runner_up": {"origin": list(grid_origin(int(order[1]))), "share": float(shares[order[1]])},
            "log10_nfa": round(float(finite_log10(main_log10_nfa)), 2),
            "significant": significant,
            "test": "votes / 64 for the most voted origin against B(X Y / 64, 1/64), times (64 X Y)^2 tests",
        },
        "vote_shares": shares.reshape(8, 8).tolist(),
        "cropped": bool(significant and main != grid_code(0, 0)),
        "log10_n_tests": round(log_nt, 3),
        "min_region_px": min_region_pixels(log_nt),
        "regions": [],
        "map": {"cell_px": cell, "tiles_shape": [shape[0] // cell, shape[1] // cell], "block_tiles": tile_factor,
                "main_share_percent": main_share},
    }

    others = np.ones(64, bool)
    if significant:
        others[main] = False
    if lum.jpeg:
        # The file's own compression grid is in every pixel of a JPEG file. Where it outvotes the main grid
        # of an earlier compression (a photo cropped off-grid and saved again at quality 98 does so over a
        # quarter to four fifths of the frame), the region has the file's history, not a foreign one.
        others[grid_code(0, 0)] = False
    labels, regions = find_regions(votes, others, log_nt)
    # Tiles are drawn only for the regions listed: (stage, region, tiles()).
    found = [("foreign", r, partial(_region_tiles, labels, r, cell)) for r in regions]
    t = _timed(marks, "foreign_regions", t)
    details["missing_tested"] = False
    if significant and params["missing_grid"]:
        if params["missing_method"] == "lattice":
            found += _lattice_stage(lum, main, details, cell)
        elif not lum.jpeg:
            # ZERO's own test; a JPEG file's every pixel went through its compression on the grid (0, 0).
            details["missing_tested"] = True
            again = _votes_of(_recompressed(lum.y, int(params["recompress_quality"]), decoding))
            again[votes == main] = -1
            labels_q, regions_q = find_regions(again, np.arange(64) == grid_code(0, 0), log_nt)
            found += [("missing", r, partial(_region_tiles, labels_q, r, cell)) for r in regions_q]
        t = _timed(marks, "missing_regions", t)
    found.sort(key=lambda f: f[1].log10_nfa)
    meaningful = [f for f in found if f[1].log10_nfa < log10_threshold]
    foreign = [f for f in meaningful if f[0] == "foreign"]
    earlier = earlier_grid(votes, main, [f[1] for f in foreign], totals) if significant else None
    cropped = set() if earlier is None else {id(foreign[i]) for i in earlier.explained}
    rest = [f for f in foreign if id(f) not in cropped]
    # A camera's first grid is the file's own unless the photo was cropped; without a main grid, as at quality
    # 100 where the file's own compression leaves few zeros, it is the only candidate.
    origins = ([grid_origin(main)] if significant else []) + ([(0, 0)] if lum.jpeg else [])
    warp = radial_warp([f[1] for f in rest], origins, shape) if origins else None
    warped = set()
    if warp is not None:
        warp, by_field = field_explained(warp, [f[1] for f in rest], labels)
        warped = {id(rest[i]) for i in by_field}
    unexplained = [f for f in rest if id(f) not in warped]
    stepped = set() if warp is not None else {id(unexplained[i]) for i in radial_steps(
        [f[1] for f in unexplained], origins, shape)}
    explained_ids = cropped | warped | stepped
    evidence = [f for f in meaningful if id(f) not in explained_ids]
    # Without a detection, the strongest candidate is kept to show how far it was from one.
    explained = [f for f in meaningful if id(f) in explained_ids]
    listed = (evidence + explained)[: int(params["max_regions_listed"])] if meaningful else found[:1]
    stages = ["cropped" if id(f) in cropped else "resampled" if id(f) in warped else
              "radial step" if id(f) in stepped else f[0] for f in listed]
    details["regions"] = [_region_record(i + 1, stage, f[1], f[2](), cell, shape, log10_threshold, stage != f[0])
                          for i, (f, stage) in enumerate(zip(listed, stages))]
    details["n_meaningful"] = len(evidence)
    details[PROCESSING_KEY] = _processing(warp, len(warped), earlier, len(cropped), details["regions"],
                                          _saved_again(lum, significant, details), len(stepped))
    _timed(marks, "report_data", t)
    details["elapsed_s"] = marks
    if not significant and not evidence and warp is None:
        return DetectorResult(Status.INCONCLUSIVE, _summary(details), details=details, headline=_headline(details))
    nfa = float(min(1.0, 10.0 ** details["regions"][0]["log10_nfa"])) if evidence else 1.0
    return DetectorResult(status=Status.OK, summary=_summary(details), score=1.0 - nfa, nfa=nfa, details=details,
                          headline=_headline(details))


class JpegGrid(Detector):
    """Regions compressed on another 8 x 8 JPEG grid than the rest of the photo, and processing that moved the grid.

    Each block votes for the grid origin at which its DCT has the most
    zeros ([1]_, [2]_); regions voting for another origin than the photo's
    main grid are found a contrario, with a number of false alarms ([3]_).

    References
    ----------
    .. [1] T. Nikoukhah, J. Anger, M. Colom, J.-M. Morel, R. Grompone von
       Gioi, ZERO: a local JPEG grid origin detector based on the number of
       DCT zeros and its applications in image forensics, Image Processing
       On Line 11, 2021.
    .. [2] T. Nikoukhah, J. Anger, T. Ehret, M. Colom, J.-M. Morel, R.
       Grompone von Gioi, JPEG grid detection based on the number of DCT
       zeros and its application to automatic and localized forgery
       detection, CVPR Workshops, 2019.
    .. [3] A. Desolneux, L. Moisan, J.-M. Morel, From Gestalt Theory to Image
       Analysis, Springer, 2008.

    Examples
    --------
    >>> from forensics_core import load_evidence
    >>> from forensics_plugins.jpeg_grid.spec import DEFAULT_PARAMS
    >>> evidence = load_evidence("tests/data/calibration/left01.jpg")
    >>> result = JpegGrid().analyze(evidence, DEFAULT_PARAMS)

    The chessboard was saved once, at about quality 50, and no region votes for another grid:

    >>> result.details["jpeg_quality_estimate"], result.details["n_meaningful"], result.nfa
    (50, 0, 1.0)
    """

    spec = SPEC

    def analyze(self, evidence: Evidence, params: Mapping[str, Any]) -> DetectorResult:
        """Run the detector on a piece of evidence (see :func:`analyse_luminance`)."""
        t = time.perf_counter()
        lum = luminance(evidence)
        elapsed = time.perf_counter() - t
        result = analyse_luminance(lum, params, evidence.decoding)
        result.details["elapsed_s"] = {"luminance": round(elapsed, 4), **result.details.get("elapsed_s", {})}
        return result

    def report_section(self, finding: DetectorFinding, evidence: Evidence) -> ReportSection | None:
        from .section import report_section

        return report_section(finding, evidence) if finding.details.get("main_grid") is not None else None

    def localize(self, finding: DetectorFinding, shape: tuple[int, int]) -> np.ndarray | None:
        """The meaningful regions' tiles, from the vote map the finding stores; None when it stores none."""
        if finding.details.get("map") is None:
            return None
        from .figures import regions_mask

        return regions_mask(finding.details, shape)

    def synthetic_cases(self, seed: int, count: int) -> Iterable[SyntheticCase]:
        """PNG and JPEG originals, pastes on another grid, and innocent crops and resamplings."""
        from .synth import synthetic_cases

        return synthetic_cases(seed, count)
