"""The dq detector: aligned double JPEG compression, block by block.

A photo saved as JPEG, edited and saved again keeps, in every block the edit
did not touch, the trace of its first quantisation; content pasted from
elsewhere (or a block rebuilt by a filter) carries it only if it happened to
keep the same 8 x 8 grid. The detector states no p-value: on real authentic
photos that were saved twice, places the photographer processed locally
before the last save (backgrounds darkened, skies retouched) vote "single" as
a pasted piece does, at NFA down to about 1e-5 on the shared corpus, so the
NFA of the most deviant window is reported as the detector's ``score``
(``min(score_cap, -log10 NFA) / score_cap``, in [0, 1]) and its strength is the likelihood ratio calibrated on real
photos.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping
from dataclasses import asdict
from typing import TYPE_CHECKING, Any

import jpeglib
import numpy as np

from forensics_core import Detector, DetectorFinding, DetectorResult, Evidence, Status

from .coefficients import ZIGZAG, LumaCoefficients, read_luma
from .primary import Primary, estimate
from .regions import overdispersion, scan
from .votes import activity, block_log_ratio, encode_votes, null_rates
from .spec import SPEC

if TYPE_CHECKING:
    from forensics_core import SyntheticCase
    from forensics_core.report import ReportSection


def _primaries(coef: LumaCoefficients, unquantised: np.ndarray, unreliable: np.ndarray,
               params: Mapping[str, Any]) -> list[tuple[tuple[int, int], Primary | None, bool]]:
    rng = np.random.default_rng(int(params["seed"]))
    out = []
    for k, flat in enumerate(ZIGZAG[1:1 + int(params["n_frequencies"])]):
        i, j = divmod(int(flat), 8)
        q2 = int(coef.table[i, j])
        found = estimate(coef.quantised[:, :, i, j][~unreliable], unquantised[:, :, k].ravel(), q2, rng)
        kept = found is not None and found.log_lik >= float(params["min_gain_nats"]) \
            and found.alpha >= float(params["min_alpha"])
        out.append(((i, j), found, kept))
    return out


def _table(primaries: list[tuple[tuple[int, int], Primary | None, bool]]) -> list[dict[str, Any]]:
    return [{"row": i, "col": j, "q2": None if p is None else p.q2, "q1": None if p is None else p.q1,
             "alpha": None if p is None else round(p.alpha, 3),
             "gain_nats": None if p is None else round(p.log_lik, 1), "used": kept}
            for (i, j), p, kept in primaries]


def votes(evidence: Evidence, params: Mapping[str, Any]) -> dict[str, Any] | None:
    """Everything the detector computes from a photo, or None when its coefficients are unreadable.

    Returns a dict with ``coef`` (:class:`.coefficients.LumaCoefficients`),
    ``primaries`` (per frequency: (row, col), Primary or None, used),
    and, when at least ``min_frequencies`` frequencies are used, the block
    maps ``log_ratio`` (nats), ``informative``, ``single``, ``unreliable``
    and ``rates``, each shape (h, w).
    """
    coef = read_luma(evidence.data)
    if coef is None or min(coef.quantised.shape[:2]) < 2:
        return None
    unreliable, unquantised = coef.scan(float(params["clip_margin"]), ZIGZAG[1:1 + int(params["n_frequencies"])])
    primaries = _primaries(coef, unquantised, unreliable, params)
    del unquantised
    out: dict[str, Any] = {"coef": coef, "primaries": primaries, "unreliable": unreliable}
    used = [(f, p) for f, p, kept in primaries if kept]
    if len(used) < int(params["min_frequencies"]):
        return out
    log_ratio = block_log_ratio(coef.quantised, [f for f, _ in used], [p for _, p in used])
    margin = float(params["vote_margin_nats"])
    informative = (np.abs(log_ratio) > margin) & ~unreliable
    single = (log_ratio < -margin) & ~unreliable
    out.update(log_ratio=log_ratio, informative=informative, single=single,
               rates=null_rates(informative, single, activity(coef.quantised)))
    return out


class DoubleQuantisation(Detector):
    """Blocks that do not carry the quantisation of the photo's earlier JPEG save (aligned double JPEG).

    References
    ----------
    .. [1] T. Bianchi, A. Piva, Image forgery localization via block-grained
       analysis of JPEG artifacts, IEEE Trans. Information Forensics and
       Security 7(3), 2012.
    .. [2] J. Lukáš, J. Fridrich, Estimation of primary quantization matrix in
       double compressed JPEG images, Digital Forensic Research Workshop, 2003.

    Examples
    --------
    A photo saved once carries no earlier quantisation, and the detector says so:

    >>> from forensics_core import load_evidence
    >>> from forensics_plugins.dq.spec import DEFAULT_PARAMS
    >>> dq = DoubleQuantisation()
    >>> print(dq.analyze(load_evidence("tests/data/calibration/left01.jpg"), DEFAULT_PARAMS).headline)
    Inconclusive: no earlier JPEG quantisation found (0 of 15 frequencies show one; 3 needed).
    """

    spec = SPEC

    def analyze(self, evidence: Evidence, params: Mapping[str, Any]) -> DetectorResult:
        """Estimate the earlier save's quantisation from the stored coefficients and map the blocks that lack it.

        Returns
        -------
        DetectorResult
            ``inconclusive`` when the coefficients are unreadable or no earlier
            quantisation is found (a photo compressed once, as a camera original
            is, or resized or cropped off its grid after the first save: this
            trace then says nothing); otherwise ``ok`` with ``score`` =
            ``min(score_cap, -log10 NFA) / score_cap`` of the most deviant window
            (0 when no window votes "single" more than expected).
        """
        t = time.perf_counter()
        found = votes(evidence, params)
        if found is None:
            return DetectorResult(Status.INCONCLUSIVE, "Inconclusive: the JPEG's DCT coefficients could not be read.",
                                  details={"jpeglib": jpeglib.__version__},
                                  headline="Inconclusive: the JPEG's DCT coefficients could not be read.")
        coef: LumaCoefficients = found["coef"]
        table = _table(found["primaries"])
        n_used = sum(r["used"] for r in table)
        details: dict[str, Any] = {
            "jpeglib": jpeglib.__version__, "blocks": list(coef.quantised.shape[:2]),
            "unreliable_blocks": int(found["unreliable"].sum()), "frequencies": table, "n_used": n_used,
        }
        if "log_ratio" not in found:
            details["elapsed_s"] = round(time.perf_counter() - t, 4)
            return DetectorResult(
                Status.INCONCLUSIVE,
                f"Inconclusive: no earlier JPEG quantisation found ({n_used} of {len(table)} frequencies show one; "
                f"{params['min_frequencies']} needed). A photo compressed once, as a camera original is, shows none; "
                f"nor does one resized or cropped off its grid after an earlier save. This trace then says nothing.",
                details=details,
                headline=f"Inconclusive: no earlier JPEG quantisation found ({n_used} of {len(table)} frequencies show "
                         f"one; {params['min_frequencies']} needed).")
        informative, single, rates = found["informative"], found["single"], found["rates"]
        rho = overdispersion(informative, single, rates)
        windows, n_tests = scan(informative, single, rates, rho, tuple(int(s) for s in params["window_blocks"]),
                                int(params["min_informative"]))
        best = windows[0] if windows else None
        cap = float(params["score_cap"])
        score = 0.0 if best is None else float(np.clip(-best.log10_nfa, 0.0, cap)) / cap
        details.update({
            "informative_blocks": int(informative.sum()), "single_votes": int(single.sum()),
            "single_rate": round(float(single.sum() / max(informative.sum(), 1)), 4), "rho": round(rho, 5),
            "n_tests": n_tests,
            "windows": [asdict(w) for w in windows if w.log10_nfa < 0][:int(params["max_windows_listed"])],
            "best": None if best is None else asdict(best),
            "block_votes": encode_votes(informative, single),
            "elapsed_s": round(time.perf_counter() - t, 4),
        })
        primary = ", ".join(f"{r['q1']}" for r in table if r["used"])
        if best is None or best.log10_nfa >= 0:
            summary = (f"An earlier JPEG save is found (primary steps {primary} on {n_used} frequencies), and no window "
                       f"of blocks lacks its trace more than the photo's own variation explains.")
            headline = (f"An earlier JPEG save shows on {n_used} frequencies; no window lacks its trace beyond the "
                        f"photo's own variation.")
        else:
            px = 8 * best.size
            summary = (f"An earlier JPEG save is found (primary steps {primary} on {n_used} frequencies). A {px} x {px} "
                       f"pixel window at ({8 * best.col}, {8 * best.row}) has {best.k} of {best.n} informative blocks "
                       f"voting single compression where {best.expected:.0%} is the photo's rate (NFA 10^"
                       f"{best.log10_nfa:.1f}). Content pasted after the earlier save looks like this; so does an area "
                       f"processed locally before the last one. Its strength is the calibrated likelihood ratio.")
            headline = (f"A {px} x {px} px window at ({8 * best.col}, {8 * best.row}) lacks the earlier JPEG "
                        f"quantisation ({best.k} of {best.n} blocks, NFA 10^{best.log10_nfa:.1f}).")
        return DetectorResult(Status.OK, summary, score=round(score, 4), details=details, headline=headline)

    def report_section(self, finding: DetectorFinding, evidence: Evidence) -> ReportSection | None:
        """The primary quantisation per frequency and the windows that vote single; generic when none was read."""
        from .section import report_section

        return report_section(finding, evidence) if "frequencies" in finding.details else None

    def localize(self, finding: DetectorFinding, shape: tuple[int, int]) -> np.ndarray:
        """The windows whose NFA is below 1."""
        return regions_mask(finding.details, shape)

    def synthetic_cases(self, seed: int, count: int) -> Iterable[SyntheticCase]:
        from .synth import synthetic_cases

        return synthetic_cases(seed, count)


def regions_mask(details: Mapping[str, Any], shape: tuple[int, int]) -> np.ndarray:
    """Pixels of the windows with NFA below 1, boolean, shape ``shape``."""
    mask = np.zeros(shape, bool)
    for w in details.get("windows") or []:
        mask[8 * w["row"]:8 * (w["row"] + w["size"]), 8 * w["col"]:8 * (w["col"] + w["size"])] = True
    return mask
