"""The lens distortion detector: from a photo's luma to a typed result.

Stages: sub-pixel edges (:mod:`.edges`), distorted straight lines
(:mod:`.lines`), per-line ``k1`` by both estimators (:mod:`.k1`), and the
global-model consistency test (:mod:`.consistency`).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from forensics_core import RADIAL_DISTORTION_KEY, Detector, DetectorFinding, DetectorResult, Evidence, RadialDistortion, Status

from .consistency import ConsistencyResult, GlobalModel, assess
from .edges import subpixel_edges
from .geometry import norm_scale, to_normalised
from .k1 import k1_paper, signed_distance, trim_to_shortest
from .lines import DistortedLine, extract_lines
from .spec import SPEC

if TYPE_CHECKING:
    from forensics_core import SyntheticCase
    from forensics_core.report import ReportSection

# Lines of at least min_length_fraction (5 %) of a side need some tens of
# edge points each; below this size there are none worth fitting.
MIN_SIDE_PX = 64



@dataclass(frozen=True)
class _Timer:
    marks: dict[str, float]

    def lap(self, stage: str, since: float) -> float:
        now = time.perf_counter()
        self.marks[stage] = round(now - since, 4)
        return now


def _decimate(points: np.ndarray, n: int) -> np.ndarray:
    """At most ``n`` points evenly spread along a line, both ends kept."""
    if len(points) <= n:
        return points
    return points[np.linspace(0, len(points) - 1, n).round().astype(int)]


def _rounded(a: np.ndarray | float, digits: int) -> Any:
    return np.round(a, digits).tolist() if isinstance(a, np.ndarray) else round(float(a), digits)


def _none_if_nan(x: float) -> float | None:
    return None if not np.isfinite(x) else float(x)


def _line_records(lines: list[DistortedLine], shape: tuple[int, int], result: ConsistencyResult,
                  params: Mapping[str, Any]) -> list[dict[str, Any]]:
    norm = [to_normalised(line.points, shape) for line in lines]
    paper_input = trim_to_shortest(norm) if params["paper_trim"] else norm
    records = []
    for i, (line, pts) in enumerate(zip(lines, norm)):
        joint = result.line_fits[i]
        dep = result.departures[i]
        records.append({
            "id": i + 1,
            "endpoints_px": _rounded(line.points[[0, -1]], 2),
            "points_px": _rounded(_decimate(line.points, int(params["points_per_line"])), 2),
            "distance": round(signed_distance(pts), 4),
            "length_px": round(line.length_px, 1),
            "n_points": len(line.points),
            "pieces": line.pieces,
            "k1": _none_if_nan(joint.k1),
            "k1_stderr": _none_if_nan(result.line_k1_stderr[i]),
            "k1_stderr_noise": _none_if_nan(joint.k1_stderr),
            "k1_paper": _none_if_nan(k1_paper(paper_input[i])),
            "residual_rms_px": _none_if_nan(joint.residual_rms_px),
            "k1_model": _none_if_nan(dep.k1),
            "delta_k1": _none_if_nan(dep.delta_k1),
            "delta_k1_stderr": _none_if_nan(dep.delta_k1_stderr),
            "z": _none_if_nan(dep.z),
            "informative": bool(dep.informative),
            "flagged": i in result.flagged_ids,
            "outlier": i in result.outlier_ids,
        })
    return records


def _global_model(result: ConsistencyResult) -> dict[str, Any] | None:
    """The photo's lens as published to other detectors: the one-term ``k1`` with the centre fitted."""
    m = result.model
    if m is None:
        return None
    one = m.one_term
    return RadialDistortion(
        k1=one.k1, k1_stderr=one.k1_stderr, k2=0.0, k2_stderr=0.0,
        cx=one.cx, cx_stderr=one.cx_stderr, cy=one.cy, cy_stderr=one.cy_stderr,
        cx_px=one.cx * m.scale_px, cy_px=one.cy * m.scale_px, sigma_px=m.sigma_px,
        n_lines_explained=m.n_lines_explained, n_lines_informative=m.n_lines_informative,
    ).to_details()


def _distortion(result: ConsistencyResult) -> dict[str, Any] | None:
    """Both fits with their uncertainty: the one-term ``k1`` as a displacement, and the two-term test model."""
    m = result.model
    if m is None:
        return None
    one = m.one_term
    se = np.sqrt(np.diag(m.covariance).clip(min=0))
    return {
        "one_term": {
            "k1": one.k1, "k1_stderr": one.k1_stderr, "cx": one.cx, "cy": one.cy,
            "covariance_k1_cx_cy": _rounded(one.covariance, 9),
            "radius": round(one.radius, 4), "radius_px": round(one.radius * m.scale_px, 1),
            "displacement_px": round(one.displacement_px, 3),
            "displacement_stderr_px": round(one.displacement_stderr_px, 3),
        },
        "two_term": {
            "k1": m.k1, "k1_stderr": m.k1_stderr, "k2": m.k2, "k2_stderr": m.k2_stderr,
            "cx": m.cx, "cx_stderr": m.cx_stderr, "cy": m.cy, "cy_stderr": m.cy_stderr,
            "covariance_k1_k2_cx_cy": _rounded(m.robust_covariance, 9),
            "model_covariance_k1_k2_cx_cy": _rounded(m.covariance, 9),
            "model_stderr": _rounded(se, 6),
        },
    }


def _paper_rules(result: ConsistencyResult) -> dict[str, Any]:
    r = result.paper_rules
    return {
        "a": {
            "rule": "distortion symmetric and growing with distance from the centre",
            "holds": not r.order_violations,
            "violating_pairs": [[i + 1, j + 1] for i, j in r.order_violations],
            "violating_line_ids": sorted({k + 1 for pair in r.order_violations for k in pair}),
        },
        "b": {
            "rule": "the same sign of k1 on every line",
            "holds": not r.sign_violators,
            "sign": {1: "barrel", -1: "pincushion", 0: "undecided"}[int(r.sign)],
            "violating_line_ids": [i + 1 for i in r.sign_violators],
        },
        "z_crit_sign": r.z_crit_sign,
        "z_crit_order": r.z_crit_order,
    }


def _region(result: ConsistencyResult) -> dict[str, Any] | None:
    """The region that departs most from one lens, whether or not it decided the test."""
    r = result.region
    if r is None:
        return None
    scale = result.model.scale_px
    return {
        "line_ids": [i + 1 for i in r.line_ids],
        "pasted_line_ids": [i + 1 for i in r.pasted_ids],
        "alternative": r.alternative,
        "donor_k1": _none_if_nan(r.donor_k1),
        "shift_px": None if not np.isfinite(r.shift[0]) else [round(r.shift[0] * scale, 1), round(r.shift[1] * scale, 1)],
        "log10_bayes_factor": _none_if_nan(r.log10_bayes_factor),
        "p_value": r.p_value,
        "n_regions": r.n_regions,
        "decided": result.evidence == "region",
    }


def _regions(records: list[dict[str, Any]]) -> list[dict[str, float]]:
    """Bounding box, pixels, of the lines of a departing region: where the pasted part is likely to be."""
    flagged = [np.asarray(r["points_px"]) for r in records if r["flagged"]]
    if not flagged:
        return []
    pts = np.vstack(flagged)
    x0, y0 = pts.min(axis=0)
    x1, y1 = pts.max(axis=0)
    return [{"x0": round(float(x0), 1), "y0": round(float(y0), 1), "x1": round(float(x1), 1), "y1": round(float(y1), 1)}]


def _lens_words(m: GlobalModel) -> str:
    """The photo's lens in words: the one-term k1 and the displacement it makes at the stated radius."""
    one = m.one_term
    return (f"k1 = {one.k1:.3f} ± {one.k1_stderr:.3f}, an undistortion of {one.displacement_px:+.1f} ± "
            f"{one.displacement_stderr_px:.1f} px at {one.radius * m.scale_px:.0f} px from the centre")


def _summary(result: ConsistencyResult, records: list[dict[str, Any]]) -> str:
    n_inf = sum(r["informative"] for r in records)
    if result.verdict == "inconclusive":
        return f"Inconclusive: {result.reason}."
    m = result.model
    if result.verdict == "inconsistent":
        ids = ", ".join(str(i + 1) for i in result.flagged_ids)
        if result.evidence == "region":
            r = result.region
            kind = (f"a compact region whose lines follow another lens, k1 about {r.donor_k1:.2f}"
                    if r.alternative == "another lens" else
                    "a compact region whose lines follow this lens about a displaced centre, as a moved copy's do")
        else:
            kind = "a single line"
        return (f"Line(s) {ids} ({kind}) depart from the lens model that explains {m.n_lines_explained} of "
                f"{n_inf} informative lines ({_lens_words(m)}; image-level p = {result.p_value:.2g}).")
    if result.outlier_ids:
        ids = ", ".join(str(i + 1) for i in result.outlier_ids)
        return (f"The {n_inf} informative lines fit one lens model ({_lens_words(m)}) except "
                f"line(s) {ids}, which depart on their own: curved or non-straight objects? The examiner should "
                f"look at them; lone departing lines are not evidence of a splice, and no compact region's lines "
                f"follow another lens (image-level p = {result.p_value:.2g}).")
    return (f"All {n_inf} informative lines fit one lens model ({_lens_words(m)}); "
            f"no line or region departs significantly (image-level p = {result.p_value:.2g}).")


def _ids(ids: list[int], shown: int = 3) -> str:
    """Line numbers for a headline: the first few, then how many more."""
    text = ", ".join(str(i) for i in ids[:shown])
    return text + (f" and {len(ids) - shown} more" if len(ids) > shown else "")


def _where(box: dict[str, float]) -> str:
    return f"x {box['x0']:.0f}–{box['x1']:.0f}, y {box['y0']:.0f}–{box['y1']:.0f}"


def _headline(result: ConsistencyResult, records: list[dict[str, Any]], regions: list[dict[str, float]]) -> str:
    """The finding in one sentence for page 1: the verdict, the lens's k1 and where any departure lies."""
    n_inf = sum(r["informative"] for r in records)
    if result.verdict == "inconclusive":
        return f"Inconclusive: {n_inf} informative straight lines of {len(records)}, too few to measure the lens."
    one = result.model.one_term
    lens = f"k1 = {one.k1:.3f} ± {one.k1_stderr:.3f}"
    p = f"p = {result.p_value:.2g}"
    if result.verdict == "inconsistent":
        flagged = [i + 1 for i in result.flagged_ids]
        ids = _ids(flagged)
        where = f" at {_where(regions[0])}" if regions else ""
        if result.evidence == "region" and result.region.alternative == "another lens":
            return (f"Lines {ids}{where} follow another lens, k1 about {result.region.donor_k1:.2f} (photo's "
                    f"{one.k1:.3f}); {p}.")
        if result.evidence == "region":
            return f"Lines {ids}{where} bend about a displaced centre, as a moved copy's do ({p})."
        lines = f"Line {ids}{where} departs" if len(flagged) == 1 else f"Lines {ids}{where} depart"
        return f"{lines} from the photo's lens model ({p})."
    if result.outlier_ids:
        return (f"{n_inf} lines fit one lens, {lens}; lines {_ids([i + 1 for i in result.outlier_ids])} depart "
                f"alone, no region departs ({p}).")
    return f"All {n_inf} informative lines fit one lens model, {lens}; no line or region departs ({p})."


def analyse(luma: np.ndarray, params: Mapping[str, Any]) -> DetectorResult:
    """Run the detector on a photo's luma.

    Parameters
    ----------
    luma : ndarray, shape (H, W)
        Luma in [0, 1], stored pixel grid.
    params : mapping
        :data:`DEFAULT_PARAMS` with the user's overrides.

    Returns
    -------
    DetectorResult
        ``ok`` with the image-level p-value of the consistency test and
        ``score = 1 - p``; ``inconclusive`` when too few informative lines.
    """
    shape = luma.shape[:2]
    if min(shape) < MIN_SIDE_PX:
        return DetectorResult(Status.INCONCLUSIVE, f"Inconclusive: the photo ({shape[1]} x {shape[0]} pixels) is too "
                              f"small to hold lines long enough to measure distortion (at least {MIN_SIDE_PX} pixels "
                              f"a side).", details={"image_size": [shape[1], shape[0]]},
                              headline=f"Inconclusive: the photo ({shape[1]} x {shape[0]} px) is too small to measure "
                                       f"lens distortion.")
    timer = _Timer({})
    t = time.perf_counter()
    edges = subpixel_edges(luma, sigma=float(params["sigma"]))
    t = timer.lap("edges", t)
    # The paper's minimum, 1/3 of the image height, leaves 0-2 lines on a real
    # building photo. What a line needs is k1 precision: a world edge's bow
    # (consistency.BOW_REL of its length) alone gives a k1 error of about
    # 13.4 BOW_REL / (d l) for normalised length l at distance d, which stays
    # below the informative limit (0.04) at d = 0.5 from l = 0.1 on, i.e.
    # 5 % of the larger side, 7 % of the shorter side of a 4:3 photo.
    # Shorter lines are kept out because they cost time and carry nothing.
    lines = extract_lines(edges, shape, float(params["min_length_fraction"]) * min(shape),
                          max_k1=float(params["max_k1"]), tolerance_px=float(params["tolerance_px"]))
    # The per-line fits cost time in proportion to the points; past a
    # hundred or so lines the longest already pin the lens down, and a pasted
    # piece has to bring long lines to be seen at all.
    lines = lines[: int(params["max_lines"])]
    t = timer.lap("lines", t)
    result = assess([line.points for line in lines], shape, alpha=float(params["alpha"]),
                    min_lines=int(params["min_lines"]), single_lines=bool(params["single_lines"]),
                    tau_k1=float(params["tau_k1"]), bow_rel=float(params["bow_rel"]), dof=float(params["dof"]),
                    tau_photo=float(params["tau_photo"]), centre_prior_sd=float(params["centre_sd"]))
    t = timer.lap("consistency", t)
    records = _line_records(lines, shape, result, params)
    timer.lap("per_line_k1", t)

    details = {
        "lines": records,
        RADIAL_DISTORTION_KEY: _global_model(result),
        "distortion": _distortion(result),
        "p_value": result.p_value if result.informative else None,
        "alpha": result.alpha,
        "test": result.test,
        "evidence": result.evidence,
        "flagged_line_ids": [i + 1 for i in result.flagged_ids],
        "outlier_line_ids": [i + 1 for i in result.outlier_ids],
        "region": _region(result),
        "regions_px": _regions(records),
        "paper_rules": _paper_rules(result),
        "n_edge_points": int(len(edges.xy)),
        "image_shape": list(shape),
        "scale_px": norm_scale(shape),
        "elapsed_s": timer.marks,
    }
    headline = _headline(result, records, details["regions_px"])
    if not result.informative:
        return DetectorResult(Status.INCONCLUSIVE, _summary(result, records), details=details, headline=headline)
    return DetectorResult(
        status=Status.OK,
        summary=_summary(result, records),
        score=1.0 - result.p_value,
        p_value=result.p_value,
        details=details,
        headline=headline,
    )


class LensDistortion(Detector):
    """Straight lines whose bow disagrees with one lens' radial distortion.

    The photo's straight edges (:mod:`.edges`, :mod:`.lines`) each give a
    ``k1`` (:mod:`.k1`); one lens model fitted to all of them
    (:mod:`.consistency`) is the null, and a region whose lines follow
    another lens or a moved copy of this one (:mod:`.regions`) the
    alternative ([1]_).

    References
    ----------
    .. [1] H. R. Chennamma, L. Rangarajan, Image splicing detection using
       inherent lens radial distortion, IJCSI 7(6), 2010.
    .. [2] F. Devernay, O. Faugeras, Straight lines have to be straight,
       Machine Vision and Applications 13, 2001.

    Examples
    --------
    The chessboard's lines all follow one lens:

    >>> from forensics_core import load_evidence
    >>> from forensics_plugins.lens_distortion.spec import DEFAULT_PARAMS
    >>> result = LensDistortion().analyze(load_evidence("tests/data/calibration/left01.jpg"), DEFAULT_PARAMS)
    >>> result.status.value, result.p_value, result.headline
    ('ok', 1.0, 'All 33 informative lines fit one lens model, k1 = 0.126 ± 0.013; no line or region departs (p = 1).')
    """

    spec = SPEC

    def analyze(self, evidence: Evidence, params: Mapping[str, Any]) -> DetectorResult:
        """Sub-pixel edges of the luma, grouped into lines, each line's k1, and their consistency with one lens."""
        return analyse(evidence.luma, params)

    def report_section(self, finding: DetectorFinding, evidence: Evidence) -> ReportSection | None:
        if finding.details.get("paper_rules") is None:
            return None
        from .section import report_section

        return report_section(finding, evidence)

    def localize(self, finding: DetectorFinding, shape: tuple[int, int]) -> np.ndarray:
        """Boolean ``(H, W)`` map of the boxes in ``details["regions_px"]`` (pixel coordinates, inclusive).

        Only an outline of where the departing lines run: the pasted part
        usually extends beyond them, so its localisation scores are a lower bound.
        """
        mask = np.zeros(shape, dtype=bool)
        h, w = shape
        for r in finding.details.get("regions_px") or []:
            x0, y0 = max(0, int(np.floor(r["x0"]))), max(0, int(np.floor(r["y0"])))
            x1, y1 = min(w - 1, int(np.ceil(r["x1"]))), min(h - 1, int(np.ceil(r["y1"])))
            mask[y0 : y1 + 1, x0 : x1 + 1] = True
        return mask

    def synthetic_cases(self, seed: int, count: int) -> Iterable[SyntheticCase]:
        """Rendered scenes of straight edges through a lens, with and without a piece from another lens."""
        from .cases import validation_cases

        return validation_cases(seed, count)
