"""The CFA detector: from a photo's stored grid to a typed result.

Stages: residual features per block (:mod:`.residuals`), the blocks' votes
for the image's mosaic phase (:mod:`.votes`), the global test and the
pattern's name (:mod:`.naming`), the content-matched null rates
(:mod:`.content_null`) and the a-contrario region scan (:mod:`.regions`),
which asks a region to disagree more than blocks of its colour do elsewhere
and the photo's own phase to be shown around it.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from forensics_core import (
    PROCESSING_KEY,
    Detector,
    DetectorFinding,
    DetectorResult,
    Evidence,
    Processing,
    RadialResampling,
    Status,
)

from . import naming
from .bayer import shifted
from .content_null import null_rates
from .drift import RULE as DRIFT_RULE, check_region
from .regions import KINDS, Question, Region, Scan, count_tests, detectable_side, scan
from .residuals import block_features
from .significance import clopper_pearson, log10_binom_tail
from .spec import JPEG_GRID, SPEC
from .votes import SHIFTS, PhaseVotes, phase_votes
from .warp import accounts_for, mosaic_warp, searched

if TYPE_CHECKING:
    from forensics_core import SyntheticCase
    from forensics_core.report import ReportSection



class _Timer:
    def __init__(self) -> None:
        self.marks: dict[str, float] = {}
        self._t = time.perf_counter()

    def lap(self, stage: str) -> None:
        now = time.perf_counter()
        self.marks[stage] = round(now - self._t, 4)
        self._t = now


def _inconclusive(reason: str, details: dict[str, Any], headline: str | None = None) -> DetectorResult:
    """An inconclusive result; ``headline`` when the reason is too long for page 1."""
    details["reason"] = reason
    return DetectorResult(Status.INCONCLUSIVE, f"Inconclusive: {reason}.", details=details,
                          headline=headline or f"Inconclusive: {reason}.")


def _colour_grid(pixels: np.ndarray) -> tuple[np.ndarray | None, float, str | None]:
    """The RGB channels of the stored grid and their full-scale value, or the reason there are none."""
    px = np.asarray(pixels)
    if px.ndim != 3 or px.shape[2] < 3:
        return None, 0.0, "the photo has no colour channels (greyscale), so it carries no colour-filter-array trace"
    rgb = px[..., :3]
    if px.dtype == np.uint8:
        full = 255.0
    elif px.dtype in (np.uint16, np.int32):
        full = 65535.0
    elif px.dtype.kind == "f":
        if not np.isfinite(rgb).all():
            return None, 0.0, "the pixel values are not all finite"
        # Float grids are taken as they are: [0, 1] unless they say otherwise.
        full = max(1.0, float(rgb.max(initial=0.0)))
    else:
        return None, 0.0, f"pixel type {px.dtype} is not supported"
    if np.array_equal(rgb[..., 0], rgb[..., 1]) and np.array_equal(rgb[..., 1], rgb[..., 2]):
        return None, 0.0, "the three colour channels are identical (a greyscale picture stored as colour)"
    return rgb, full, None


def _rate(k: int, n: int) -> dict[str, Any]:
    lo, hi = clopper_pearson(k, n)
    return {"agree": k, "votes": n, "rate": (k / n) if n else None, "ci95": [lo, hi] if n else None,
            "log10_p": float(log10_binom_tail(np.array([k]), np.array([n]), 0.5)[0]) if n else 0.0}


def _power(grid: tuple[int, int], rate: float | None, vote_rate: float, n_tests: int, eps: float) -> dict[str, Any]:
    side = detectable_side(grid, rate, vote_rate, n_tests, eps) if rate and rate > 0.5 else None
    return {"side_blocks": side,
            "fraction": None if side is None else side * side / (grid[0] * grid[1])}


def _region_record(region: Region, block: int, shape: tuple[int, int], index: int) -> dict[str, Any]:
    rows, cols = np.nonzero(region.blocks)
    y0, x0, h, w = region.window
    return {
        "id": index,
        "kind": region.kind,
        "log10_nfa": round(region.log10_nfa, 3),
        "nfa": float(10.0 ** region.log10_nfa),
        "n_blocks": int(len(rows)),
        "area_fraction": len(rows) * block * block / (shape[0] * shape[1]),
        "bbox_px": [int(cols.min() * block), int(rows.min() * block),
                    int((cols.max() + 1) * block), int((rows.max() + 1) * block)],
        "window_px": [x0 * block, y0 * block, (x0 + w) * block, (y0 + h) * block],
        "votes_against": region.votes_against,
        "votes": region.votes,
        "null_rate": round(region.null_rate, 4),
        "ring_agree": region.ring_agree,
        "ring_votes": region.ring_votes,
        "blocks": np.stack([rows, cols], axis=1).tolist(),
    }


def regions_mask(details: Mapping[str, Any], shape: tuple[int, int]) -> np.ndarray:
    """Boolean ``(H, W)`` map of the blocks of every flagged region (all False when none)."""
    mask = np.zeros(shape, dtype=bool)
    block = int(details.get("block_px", 0) or 0)
    for region in details.get("regions") or []:
        for row, col in region["blocks"]:
            mask[row * block:(row + 1) * block, col * block:(col + 1) * block] = True
    return mask


def _drifted(votes: PhaseVotes, questions: list[Question], chroma: np.ndarray, plain: Scan, block: int,
             shape: tuple[int, int], eps: float) -> tuple[list[dict[str, Any] | None], list[Question], Scan]:
    """The regions a smooth drift of the whole mosaic explains, and the scan without them (:mod:`.drift`).

    Each region of ``plain`` is checked against the drift of the voting
    blocks outside it; the blocks of the regions explained abstain from
    ``questions`` and the scan is run again.
    Returns every region's check (its record, None where too few blocks
    vote), and the questions and scan to go on with: ``plain``'s own when
    no region is explained.
    """
    checks = [check_region(votes.shift_vote, votes.usable, r.blocks, block, shape) for r in plain.regions]
    explained = [r for r, c in zip(plain.regions, checks) if c is not None and c.explained]
    records = [None if c is None else c.record() for c in checks]
    if not explained:
        return records, questions, plain
    away = ~np.any([r.blocks for r in explained], axis=0)
    kept = [Question(q.kind, q.disagree, q.voting & away, null_rates(q.disagree, q.voting & away, chroma))
            for q in questions]
    return records, kept, scan(kept, eps)


def analyse(pixels: np.ndarray, params: Mapping[str, Any], warp: RadialResampling | None = None) -> DetectorResult:
    """Run the detector on a photo's stored grid.

    Parameters
    ----------
    pixels : ndarray, shape (H, W) or (H, W, C)
        The evidence's stored grid (read only).
    params : mapping
        :data:`DEFAULT_PARAMS` with the user's overrides.
    warp : RadialResampling, optional
        A lens correction of the whole photo that ``jpeg_grid`` established.
        When the blocks' votes follow the phases its displacement, rounded
        to whole pixels, gives them, the correction is published as
        processing (``details["processing"]``) and regions are those that
        depart from the phase it gave each block, not from the photo's one
        phase (:mod:`.warp`). Without it, when regions of another phase
        appear, a one-term warp proposed by the mosaic itself is tried
        (:func:`.warp.searched`), and used when the mosaic follows it and it
        accounts for the other-diagonal blocks (:func:`.warp.accounts_for`).

    Returns
    -------
    DetectorResult
        ``ok`` with the NFA of the most significant region (or of the most
        significant window when no region is flagged) and ``score = 1 -
        min(1, NFA)``; ``inconclusive`` when the photo has no colour, is too
        small, or carries too weak a demosaicing trace: outside any region
        found, its blocks must agree with its phase well enough that a paste
        of :data:`DEFAULT_PARAMS` ``max_detectable_fraction`` of the photo
        would be flagged. Regions found in a photo that fails this are listed
        in ``details["regions_set_aside"]``, not flagged.
    """
    timer = _Timer()
    block = int(params["block_px"])
    eps = float(params["nfa_threshold"])
    details: dict[str, Any] = {
        "image_shape": list(np.shape(pixels)[:2]),
        "block_px": block,
        "thresholds": {"trace_alpha": float(params["trace_alpha"]), "nfa_threshold": eps,
                       "max_detectable_fraction": float(params["max_detectable_fraction"])},
    }
    rgb, full, reason = _colour_grid(pixels)
    if rgb is None:
        return _inconclusive(reason, details)
    h, w = rgb.shape[:2]
    ny, nx = h // block, w // block
    if ny < 8 or nx < 8:
        return _inconclusive(f"the photo ({w} x {h} pixels) is too small: at least 8 x 8 blocks of {block} pixels "
                             "are needed", details)

    feats = block_features(rgb, block, full, float(params["log_offset"]))
    timer.lap("residuals")
    usable = ((feats.clipped <= float(params["max_clipped_fraction"]))
              & (feats.activity >= float(params["min_activity"])))
    details.update({"grid": [ny, nx], "n_usable": int(usable.sum()), "usable_fraction": float(usable.mean())})
    if usable.sum() < int(params["min_usable_blocks"]):
        return _inconclusive(f"only {int(usable.sum())} blocks have unclipped texture (at least "
                             f"{int(params['min_usable_blocks'])} needed)", details)

    try:
        votes = phase_votes(feats.features, feats.colour, usable, float(params["shrinkage"]),
                            float(params["colour_ridge"]))
    except ValueError as exc:
        return _inconclusive(f"the signature of the mosaic cannot be learnt: {exc}", details,
                             "Inconclusive: the signature of the photo's mosaic cannot be learnt.")
    timer.lap("votes")
    diag_voting = usable & (votes.t_diag != 0)
    rb_voting = usable & (votes.t_diag > 0) & (votes.t_rb != 0)
    diag = _rate(int((votes.t_diag > 0).sum()), int(diag_voting.sum()))
    rb = _rate(int((rb_voting & (votes.t_rb > 0)).sum()), int(rb_voting.sum()))
    n_tests = len(KINDS) * count_tests(ny, nx)
    details.update({
        "features": [f"{source} {kind}" for source, kind in feats.names],
        "signature": np.round(votes.signature, 4),
        "diagonal": diag,
        "red_blue": rb,
        "shift_votes": votes.shift_vote.astype(int),
        "shifts": [list(s) for s in SHIFTS],
        "n_tests": n_tests,
    })
    trace = diag["log10_p"] <= np.log10(float(params["trace_alpha"]))
    details["trace_present"] = bool(trace)
    if not trace:
        timer.lap("scan")
        details["elapsed_s"] = timer.marks
        return _inconclusive("no demosaicing trace: the blocks do not agree on a mosaic phase better than chance "
                             f"({diag['agree']} of {diag['votes']} votes, p = {10 ** diag['log10_p']:.2g}); strong "
                             "compression, resizing or a non-Bayer camera erase it", details,
                             f"Inconclusive: no demosaicing trace; blocks' agreement on one mosaic phase, "
                             f"{diag['agree']} of {diag['votes']}, is not significant "
                             f"(p = {10 ** diag['log10_p']:.2g}).")

    name = naming.name_pattern(rgb, votes, block, full)
    timer.lap("naming")
    details["pattern"] = name

    chroma = np.stack([feats.colour, feats.green], axis=2)
    mosaic = mosaic_warp(warp, votes.t_diag, diag_voting, block, (h, w)) if warp is not None else None
    follows = mosaic is not None and mosaic.follows

    def scanned(follows: bool) -> tuple[list[Question], dict[str, float], Scan]:
        # In a photo whose mosaic a lens correction moved, each block is asked about the phase it was given.
        asked = (mosaic.questions(votes.t_diag, votes.t_rb, diag_voting, rb_voting) if follows else
                 (("diagonal", votes.t_diag < 0, diag_voting), ("red_blue", votes.t_rb < 0, rb_voting)))
        questions, share = [], {}
        for kind, disagree, voting in asked:
            null = null_rates(disagree, voting, chroma)
            # Reported: how much of the photo is of a colour that votes against as a rule.
            share[kind] = round(float((null[voting] > 0.5).mean()), 4) if voting.any() else 0.0
            questions.append(Question(kind, disagree, voting, null))
        return questions, share, scan(questions, eps)

    questions, share, result = scanned(follows)
    warp_source = "jpeg_grid"
    explained: list[tuple[Region, dict[str, Any]]] = []
    if result.regions and not follows:
        plain = result
        checks, _, drifted = _drifted(votes, questions, chroma, plain, block, (h, w), eps)
        explained = [(r, c) for r, c in zip(plain.regions, checks) if c is not None and c["explained"]]
        # A drift explains a region by the mosaic around it; failing that, the whole mosaic may follow a lens
        # correction jpeg_grid could not establish, proposed by the blocks themselves.
        candidate = None
        if not explained and warp is None:
            proposed = searched(votes.t_diag, diag_voting, block, (h, w))
            candidate = mosaic_warp(proposed[0], votes.t_diag, diag_voting, block, (h, w), proposed[1]) \
                if proposed is not None else None
        accounts = candidate is not None and accounts_for(candidate, votes.t_diag, diag_voting)
        if candidate is not None and candidate.follows and accounts:
            mosaic, follows, warp_source = candidate, True, "the mosaic itself"
            _, share, result = scanned(True)
        else:
            if candidate is not None:
                details["warp_searched"] = {**candidate.record(), "accounts_for_other_diagonal": accounts}
            details["drift_checks"] = {"rule": DRIFT_RULE, "regions": checks}
            result = drifted
    details["colour_against_share"] = share
    if explained:
        span = max(c["span_px"] for _, c in explained)
        details[PROCESSING_KEY] = Processing(
            "slight resampling", f"resampled slightly as a whole after demosaicing: its colour mosaic drifts "
            f"smoothly by up to {span:.1f} px across the frame, as when a camera scales its sensor's image to the "
            "output size or an editor slightly resizes, rotates or shears the photo").to_details()
    timer.lap("scan")
    vote_rate = diag["votes"] / (ny * nx)
    details["power"] = {
        "diagonal": _power((ny, nx), diag["rate"], vote_rate, n_tests, eps),
        "red_blue": _power((ny, nx), rb["rate"], rb["votes"] / (ny * nx), n_tests, eps),
    }
    regions = [_region_record(r, block, (h, w), i + 1) for i, r in enumerate(result.regions)]
    if explained:
        details["regions_explained"] = [{**{k: v for k, v in _region_record(r, block, (h, w), i + 1).items()
                                            if k != "blocks"}, "drift": c} for i, (r, c) in enumerate(explained)]
    if name["pattern"]:
        for rec, r in zip(regions, result.regions):
            sv = votes.shift_vote[r.blocks]
            counts = np.bincount(sv[sv >= 0], minlength=4)
            counts[0] = 0
            rec["pattern"] = shifted(name["pattern"], *SHIFTS[int(np.argmax(counts))])
    details["regions"] = regions
    details["min_log10_nfa"] = round(result.min_log10_nfa, 3)
    if follows:
        details[PROCESSING_KEY] = {
            **Processing("radial resampling", "resampled by a radial warp about its centre, which moved its colour "
                         "mosaic by whole pixels in rings, as lens correction does").to_details(),
            "mosaic": {**mosaic.record(), "warp_from": warp_source},
        }
    elif mosaic is not None:
        details["warp_checked"] = mosaic.record()
    details["elapsed_s"] = timer.marks

    # The photo's own trace is judged outside the regions, which would dilute it.
    outside = diag_voting & ~np.any([r.blocks for r in result.regions], axis=0) if regions else diag_voting
    if follows:
        host = _rate(*mosaic.agreement(votes.t_diag, outside))
    else:
        host = _rate(int((outside & (votes.t_diag > 0)).sum()), int(outside.sum()))
    fraction = _power((ny, nx), host["rate"], vote_rate, n_tests, eps)["fraction"]
    details["power"]["diagonal_outside_regions"] = fraction
    if fraction is None or fraction > float(params["max_detectable_fraction"]):
        # A paste from a photo like this one would disagree no more than the
        # photo agrees, so where that is too weak to localise a tenth of the
        # photo, a region found anyway owes its votes to an area of content
        # (measured on camera JPEGs), not to another mosaic.
        details["regions"] = []
        details["regions_set_aside"] = [{k: v for k, v in r.items() if k != "blocks"} for r in regions]
        limit = "the whole photo" if fraction is None else f"{100 * fraction:.0f}% of the photo"
        aside = (f"; {len(regions)} area(s) voting against it were set aside, as content at this trace strength "
                 "cannot be told from another mosaic") if regions else ""
        return _inconclusive(f"the demosaicing trace is too weak to localise a pasted region smaller than {limit} "
                             f"(blocks agree with the photo's phase at a rate of {host['rate'] or 0:.2f}){aside}",
                             details,
                             f"Inconclusive: the demosaicing trace (agreement {host['rate'] or 0:.2f}) is too weak "
                             f"to localise a paste smaller than {limit}.")
    nfa = regions[0]["nfa"] if regions else float(10.0 ** result.min_log10_nfa)
    return DetectorResult(
        status=Status.OK,
        summary=_summary(details, regions, nfa),
        score=1.0 - min(1.0, nfa),
        nfa=nfa,
        details=details,
        headline=_headline(details, regions, nfa),
    )


def _lens_corrected(details: Mapping[str, Any]) -> bool:
    """Whether each block was judged against the phase jpeg_grid's lens correction gave it."""
    return "mosaic" in details.get(PROCESSING_KEY, {})


def _processing_text(details: dict[str, Any]) -> str:
    """The processing the mosaic shows, as a sentence for the summary (empty when none)."""
    processing = details.get(PROCESSING_KEY)
    if not processing:
        return ""
    explained = details.get("regions_explained")
    if explained:
        span = max(r["drift"]["span_px"] for r in explained)
        gain = min(r["drift"]["outside_gain_nats"] for r in explained)
        return (f" {len(explained)} area(s) voting for another phase follow a smooth drift of the whole mosaic, by up "
                f"to {span:.1f} px across the frame: a displacement varying linearly across the photo explains the "
                f"votes around them better than one phase (by {gain:.0f} nats or more) and predicts those areas' "
                "phase. The photo was resampled slightly as a whole, which is processing; those areas were set aside "
                "and the photo scanned again without them.")
    m = processing["mosaic"]
    p = f"{10 ** m['log10_p']:.1g}" if m["log10_p"] > -300 else f"10^{m['log10_p']:.0f}"
    found = ("that jpeg_grid found" if m.get("warp_from", "jpeg_grid") == "jpeg_grid" else
             "that its own phases show (a one-term radial profile searched on the blocks, accounting for most of "
             "those on the other diagonal)")
    return (f" The mosaic follows the lens correction {found}, moved by its displacement rounded to "
            f"whole pixels (blocks agree with the phase it predicts on {m['agree']} of {m['votes']}, p = {p}): "
            "that is processing, and each block was judged against the phase the correction gave it.")


def _nfa_text(log10_nfa: float) -> str:
    """An NFA for a sentence; powers of ten below what a float holds."""
    return f"{10 ** log10_nfa:.2g}" if log10_nfa > -300 else f"10^{log10_nfa:.0f}"


def _headline(details: dict[str, Any], regions: list[dict[str, Any]], nfa: float) -> str:
    """The finding in one sentence for page 1: where a region departs, or the phase held throughout."""
    if not regions and details.get("regions_explained"):
        return (f"The mosaic drifts smoothly across the frame, a slight resampling of the whole photo (processing); no "
                f"other region departs (smallest NFA {nfa:.2g}).")
    if not regions and _lens_corrected(details):
        return (f"The mosaic follows a lens correction's warp (processing); no region departs from the phase it gave "
                f"each block (smallest NFA {nfa:.2g}).")
    if not regions:
        return (f"One demosaicing phase throughout (blocks agree at {details['diagonal']['rate']:.2f}); no region "
                f"departs (smallest NFA {nfa:.2g}).")
    r = regions[0]
    x0, y0, x1, y1 = r["bbox_px"]
    more = f", with {len(regions) - 1} more region(s)," if len(regions) > 1 else ""
    return (f"Region at x {x0}–{x1}, y {y0}–{y1} ({100 * r['area_fraction']:.1f}% of the photo){more} has another "
            f"demosaicing phase (NFA {_nfa_text(r['log10_nfa'])}).")


def _summary(details: dict[str, Any], regions: list[dict[str, Any]], nfa: float) -> str:
    pattern = details["pattern"]["pattern"]
    where = f"a {pattern} Bayer mosaic" if pattern else "a Bayer mosaic (pattern name undetermined)"
    rate = details["diagonal"]["rate"]
    processing = _processing_text(details)
    if not regions and _lens_corrected(details):
        return (f"The photo carries the trace of {where}; no region departs from the phase its lens correction gave "
                f"each block (smallest NFA {nfa:.2g}).{processing}")
    if not regions and processing:
        return (f"The photo carries the trace of {where}; no region departs from its phase but those the drift of "
                f"its mosaic explains (smallest NFA {nfa:.2g}).{processing}")
    if not regions:
        frac = details["power"]["diagonal"]["fraction"]
        return (f"The photo carries the trace of {where} in one phase throughout (blocks agree at a rate of "
                f"{rate:.2f}); no region with another phase was found (smallest NFA {nfa:.2g}; a region of "
                f"{100 * frac:.1f}% of the photo or more would have been found).")
    r = regions[0]
    kind = "green on the other diagonal" if r["kind"] == "diagonal" else "red and blue swapped"
    more = f" and {len(regions) - 1} more" if len(regions) > 1 else ""
    against = ("the phase the photo's lens correction gave it" if _lens_corrected(details)
               else "the photo's demosaicing phase")
    return (f"Region 1{more} ({100 * r['area_fraction']:.1f}% of the photo, {kind}) disagrees with {against} "
            f"({where}), NFA = {_nfa_text(r['log10_nfa'])}.{processing}")


class ColourFilterArray(Detector):
    """Blocks whose demosaicing phase departs from the photo's colour filter array (Bayer) grid.

    Each 2 x 2 phase of the Bayer mosaic is tested per block by how well the
    demosaicing a camera applies explains the block ([1]_, [2]_); regions
    that vote for another phase than the photo's, or for none, are found
    a contrario, with a number of false alarms ([3]_).

    References
    ----------
    .. [1] A. C. Popescu, H. Farid, Exposing digital forgeries in color filter
       array interpolated images, IEEE Trans. Signal Processing 53(10), 2005.
    .. [2] Q. Bammey, R. Grompone von Gioi, J.-M. Morel, Demosaicing to detect
       demosaicing and image forgeries, IEEE WIFS 2022.
    .. [3] A. Desolneux, L. Moisan, J.-M. Morel, From Gestalt Theory to Image
       Analysis, Springer, 2008.

    Examples
    --------
    This camera photo's JPEG compression has erased the mosaic, so there is
    nothing to compare and the detector declines:

    >>> from forensics_core import load_evidence
    >>> from forensics_plugins.cfa.spec import DEFAULT_PARAMS
    >>> result = ColourFilterArray().analyze(load_evidence("tests/data/exif/87_OSError.jpg"), DEFAULT_PARAMS)
    >>> result.status.value, result.details["trace_present"], result.details["grid"]
    ('inconclusive', False, [140, 93])
    """

    spec = SPEC

    def analyze(self, evidence: Evidence, params: Mapping[str, Any],
                prior: Mapping[str, DetectorFinding] | None = None) -> DetectorResult:
        """The stored RGB grid's per-block phase votes and the regions that vote for another phase.

        ``prior`` may hold ``jpeg_grid``'s finding: a lens correction it
        established explains the regions its warp moved onto the other diagonal.
        """
        return analyse(evidence.pixels, params, RadialResampling.from_finding((prior or {}).get(JPEG_GRID)))

    def report_section(self, finding: DetectorFinding, evidence: Evidence) -> ReportSection | None:
        """The vote map, the flagged regions and their tests; the generic section when no thresholds were set."""
        from .section import report_section

        return report_section(finding, evidence) if finding.details.get("thresholds") else None

    def localize(self, finding: DetectorFinding, shape: tuple[int, int]) -> np.ndarray:
        return regions_mask(finding.details, shape)

    def synthetic_cases(self, seed: int, count: int) -> Iterable[SyntheticCase]:
        """Demosaiced scenes, authentic and with a piece pasted on another phase or resampled."""
        from .synth import synthetic_cases

        return synthetic_cases(seed, count)
