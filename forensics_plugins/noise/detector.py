"""The noise detector: regions whose fine-grain noise differs from like content elsewhere in the photo.

Content pasted from another photo brings that photo's noise: another sensor,
ISO, denoising, or a resize that smoothed it (enlarged) or concentrated it
(reduced). The detector measures each 8 x 8 block's fine-grain energy
(:mod:`.blocks`), compares it with blocks of like grey level and texture
(:mod:`.residuals`) and reports the window that departs most from the
photo's own windows (:mod:`.windows`). It states no p-value: real photos'
noise varies in space with in-camera processing and the scene, so the
deviation is reported as the detector's ``score``
(``min(score_cap, |deviation|) / score_cap``, in [0, 1]) and its strength is
the likelihood ratio calibrated on real photos.
"""

from __future__ import annotations

import base64
import time
import zlib
from collections.abc import Iterable, Mapping
from dataclasses import asdict
from typing import TYPE_CHECKING, Any

import numpy as np

from forensics_core import Detector, DetectorFinding, DetectorResult, Evidence, Status

from .blocks import BLOCK, measure
from .residuals import standardised
from .windows import distinct, scan
from .spec import SPEC

if TYPE_CHECKING:
    from forensics_core import SyntheticCase
    from forensics_core.report import ReportSection

Z_ENCODING = "int8 z*25, row-major, zlib, base64"
_Z_STEP = 25.0


def encode_z(z: np.ndarray, used: np.ndarray) -> dict[str, Any]:
    """The block z-scores as the finding carries them, so that the report draws them without recomputing.

    Parameters
    ----------
    z : ndarray, shape (h, w)
        Clipped to [-5, 5] (the default ``z_clip`` is 4).
    used : ndarray of bool, shape (h, w)
        Blocks not used are stored as -128.
    """
    codes = np.where(used, np.clip(np.round(z * _Z_STEP), -125, 125), -128).astype(np.int8)
    return {"shape": list(codes.shape), "encoding": Z_ENCODING,
            "data": base64.b64encode(zlib.compress(codes.tobytes(), 9)).decode("ascii")}


def decode_z(record: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """``(z, used)``, shapes (h, w), from :func:`encode_z`'s record."""
    if record.get("encoding") != Z_ENCODING:
        raise ValueError(f"unknown z-map encoding {record.get('encoding')!r}")
    shape = tuple(int(v) for v in record["shape"])
    codes = np.frombuffer(zlib.decompress(base64.b64decode(record["data"])), np.int8).reshape(shape)
    used = codes != -128
    return np.where(used, codes / _Z_STEP, 0.0), used


def regions_mask(details: Mapping[str, Any], shape: tuple[int, int]) -> np.ndarray:
    """Pixels of the listed windows, boolean, shape ``shape``."""
    mask = np.zeros(shape, bool)
    for w in details.get("windows") or []:
        mask[BLOCK * w["row"]:BLOCK * (w["row"] + w["size"]), BLOCK * w["col"]:BLOCK * (w["col"] + w["size"])] = True
    return mask


class NoiseLevel(Detector):
    """Windows whose local noise level departs from the rest of the photo's.

    References
    ----------
    .. [1] B. Mahdian, S. Saic, Using noise inconsistencies for blind image
       forensics, Image and Vision Computing 27(10), 2009.
    .. [2] S. Lyu, X. Pan, X. Zhang, Exposing region splicing forgeries with
       blind local noise estimation, International Journal of Computer
       Vision 110(2), 2014.

    Examples
    --------
    >>> from forensics_core import load_evidence
    >>> from forensics_plugins.noise.spec import DEFAULT_PARAMS

    Of the 575 windows compared on the chessboard, none departs:

    >>> result = NoiseLevel().analyze(load_evidence("tests/data/calibration/left01.jpg"), DEFAULT_PARAMS)
    >>> result.details["n_windows"], result.details["windows"]
    (575, [])
    """

    spec = SPEC

    def analyze(self, evidence: Evidence, params: Mapping[str, Any]) -> DetectorResult:
        """Measure each block's noise level and find the windows that depart from the photo's.

        Returns
        -------
        DetectorResult
            ``inconclusive`` when fewer than ``min_blocks`` blocks can be
            compared (a small photo, or one mostly clipped to black or white),
            when all of them have the same fine-grain energy (no noise at all),
            or when no window can be measured; otherwise ``ok`` with ``score`` =
            ``min(score_cap, |deviation|) / score_cap`` of the most deviant window.

        Examples
        --------
        >>> from forensics_core import load_evidence
        >>> from forensics_plugins.noise.spec import DEFAULT_PARAMS
        >>> result = NoiseLevel().analyze(load_evidence("photo.jpg"), DEFAULT_PARAMS)  # doctest: +SKIP
        >>> result.details["best"]["deviation"]  # doctest: +SKIP
        3.2
        """
        t = time.perf_counter()
        lo, hi = params["clip_levels"]
        features = measure(evidence.luma, int(params["fine_min_order"]), int(params["coarse_max_order"]),
                           float(params["energy_floor"]), (float(lo), float(hi)))
        details: dict[str, Any] = {"blocks": list(features.valid.shape), "valid_blocks": int(features.valid.sum())}
        if details["valid_blocks"] < int(params["min_blocks"]):
            details["elapsed_s"] = round(time.perf_counter() - t, 4)
            return DetectorResult(
                Status.INCONCLUSIVE,
                f"Inconclusive: {details['valid_blocks']} blocks of 8 x 8 pixels are neither clipped to black or white "
                f"nor past the edge; {params['min_blocks']} are needed to compare noise between regions.",
                details=details,
                headline=f"Inconclusive: only {details['valid_blocks']} unclipped 8 x 8 blocks ({params['min_blocks']} "
                         f"needed) to compare noise between regions.")
        if np.ptp(features.energy[features.valid]) == 0:
            details["elapsed_s"] = round(time.perf_counter() - t, 4)
            return DetectorResult(
                Status.INCONCLUSIVE,
                "Inconclusive: every block has the same fine-grain energy (a synthetic or flattened picture without "
                "noise), so there is no noise to compare between regions.", details=details,
                headline="Inconclusive: every block has the same fine-grain energy; there is no noise to compare.")
        z, used = standardised(features, int(params["intensity_bins"]), int(params["texture_bins"]),
                               int(params["min_cell_blocks"]), float(params["scale_floor"]), float(params["z_clip"]))
        windows, spreads = scan(z, used, tuple(int(f) for f in params["window_fractions"]),
                                int(params["min_window_blocks"]), float(params["min_valid_share"]))
        details.update({"used_blocks": int(used.sum()), "spreads": {str(k): v for k, v in spreads.items()},
                        "n_windows": len(windows)})
        if not windows:
            details["elapsed_s"] = round(time.perf_counter() - t, 4)
            return DetectorResult(
                Status.INCONCLUSIVE,
                "Inconclusive: too few windows have enough comparable blocks to measure how noise varies in this "
                "photo.", details=details,
                headline="Inconclusive: too few windows have enough comparable blocks to measure how noise varies.")
        best = windows[0]
        listed = distinct(windows, float(params["list_threshold"]), int(params["max_windows_listed"]))
        cap = float(params["score_cap"])
        details.update({
            "best": asdict(best),
            "windows": [asdict(w) for w in listed],
            "z_map": encode_z(z, used),
            "elapsed_s": round(time.perf_counter() - t, 4),
        })
        px = BLOCK * best.size
        kind = "noisier than" if best.deviation > 0 else "smoother than" if best.deviation < 0 else "as noisy as"
        summary = (f"The window departing most is {px} x {px} pixels at ({BLOCK * best.col}, {BLOCK * best.row}): "
                   f"{kind} content of like grey level and texture elsewhere, {abs(best.deviation):.1f} times the "
                   f"spread of the photo's own windows of that size. "
                   + (f"{len(listed)} window(s) depart by {params['list_threshold']} or more. " if listed else
                      f"No window departs by {params['list_threshold']} or more. ")
                   + "Noise varies in authentic photos too (denoising, sharpening, the scene); the strength is the "
                     "calibrated likelihood ratio.")
        headline = (f"Window of {px} px at ({BLOCK * best.col}, {BLOCK * best.row}) is {kind} like content elsewhere "
                    f"by {abs(best.deviation):.1f} spreads; {len(listed)} window(s) depart by {params['list_threshold']} "
                    f"or more.")
        return DetectorResult(Status.OK, summary, score=round(min(abs(best.deviation), cap) / cap, 4), details=details,
                              headline=headline)

    def report_section(self, finding: DetectorFinding, evidence: Evidence) -> ReportSection | None:
        """The block noise map and the departing windows; the generic section when no block was measured."""
        from .section import report_section

        return report_section(finding, evidence) if "blocks" in finding.details else None

    def localize(self, finding: DetectorFinding, shape: tuple[int, int]) -> np.ndarray:
        return regions_mask(finding.details, shape)

    def synthetic_cases(self, seed: int, count: int) -> Iterable[SyntheticCase]:
        """Scenes with a pasted piece of another noise level, and authentic ones with flat and textured areas."""
        from .synth import synthetic_cases

        return synthetic_cases(seed, count)
