"""The prnu detector: fingerprint from the references, the photo's alignment and PCE, then the local map.

Pipeline: :mod:`.cache` (the fingerprint of the reference set,
:mod:`.fingerprint`) -> :mod:`.residual` (the photo's noise residual) ->
:mod:`.alignment` (orientation, crop, scale; the PCE of :mod:`.pce`) ->
:mod:`.likelihood` (the source LR) -> :mod:`.local` (blocks without the
fingerprint) -> :mod:`.likelihood` (the manipulation LR).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from forensics_core import ATTRIBUTION_KEY, Detector, DetectorResult, Evidence, ReferenceSet, SourceAttribution, Status
from forensics_core.report import lr_text

from .alignment import aligned, best_alignment, single_test_z
from .cache import fingerprint_for
from .likelihood import shipped
from .local import boxes as region_boxes
from .local import local_map, regions
from .residual import eight_bit, test_residual
from .spec import SPEC


HP_SOURCE = "the photo was taken by the camera that took the reference photos"
HD_SOURCE = "the photo was taken by another camera of the same model"


class Prnu(Detector):
    """Sensor fingerprint (PRNU) against reference photos of the claimed camera.

    Examples
    --------
    >>> from forensics_plugins.prnu.detector import Prnu
    >>> Prnu.spec.name, Prnu.spec.uses_reference
    ('prnu', True)
    """

    spec = SPEC

    def analyze(self, evidence: Evidence, params: Mapping[str, Any], reference: ReferenceSet) -> DetectorResult:
        try:
            fingerprint, cached = fingerprint_for(reference, float(params["sigma0"]))
        except ValueError as exc:
            return DetectorResult(Status.INCONCLUSIVE, f"No fingerprint could be estimated: {exc}.",
                                  details={"reference": {"count": len(reference)}},
                                  headline="No fingerprint: the reference photos differ in size.")
        ref = {"count": fingerprint.count, "digest": reference.digest, "cached": cached,
               "frame": [int(fingerprint.shape[1]), int(fingerprint.shape[0])],
               "files": [{"name": r.name, "sha256": r.sha256} for r in reference.records]}
        residual, intensity = test_residual(eight_bit(evidence.pixels), float(params["sigma0"]))
        peak = best_alignment(intensity * residual, fingerprint.k)
        if peak is None:
            return DetectorResult(
                Status.INCONCLUSIVE,
                f"The photo ({evidence.info.width}x{evidence.info.height}) is larger than the references' frame "
                f"({ref['frame'][0]}x{ref['frame'][1]}) in every orientation, so it cannot come from that "
                f"camera's sensor unscaled; an enlarged photo is not tested.",
                details={"reference": ref}, headline="Not tested: the photo is larger than the reference frame.")
        z = single_test_z(peak)
        models = shipped()
        source = models.attribution_log10_lr(z) if models else None
        details: dict[str, Any] = {
            "reference": ref,
            "alignment": {"rotation": peak.rotation, "shift": list(peak.shift), "scale": round(peak.scale, 6),
                          "searched": peak.searched},
            "pce": round(peak.pce, 3), "z": round(z, 4), "min_pce": params["min_pce"],
            "attribution_log10_lr": None if source is None else round(source, 4),
            "calibration": models.data if models else None,
        }
        if source is not None:
            details[ATTRIBUTION_KEY] = SourceAttribution(
                hp=HP_SOURCE, hd=HD_SOURCE, log10_lr=round(source, 4),
                basis=f"the peak-to-correlation energy of the reference camera's sensor fingerprint in the photo "
                      f"({peak.pce:.4g})").to_details()
        attribution = (f"PCE {peak.pce:.4g} at rotation {peak.rotation} deg, shift {peak.shift}, scale "
                       f"{peak.scale:.3g} ({peak.searched} alignments searched)")
        if source is not None:
            attribution += (f"; source LR {lr_text(source)} for \"taken by the reference camera\" against "
                            f"\"another camera of the same model\"")
        if peak.pce < params["min_pce"]:
            return DetectorResult(
                Status.INCONCLUSIVE,
                f"The reference camera's fingerprint was not found in the photo ({attribution}; below the detection "
                f"threshold {params['min_pce']:g}), so no part of it can be checked for the fingerprint.",
                details=details, headline=f"Fingerprint not found (PCE {peak.pce:.3g}); parts not checked.")
        (turned_residual, turned_intensity), k = aligned((residual, intensity), peak, fingerprint.k)
        block = int(params["block"])
        local = local_map(turned_residual, turned_intensity, k, block, max(1, block // 4))
        flagged, best = regions(local, float(params["region_llr"]))
        boxes = region_boxes(flagged, local.block, local.step, peak.rotation, turned_residual.shape)
        log10_lr = models.manipulation_log10_lr(best) if models else None
        details["local"] = {
            "block": local.block, "step": local.step, "sigma0": round(local.sigma0, 6),
            "decidable_share": round(float(local.decidable.mean()), 4), "best_window_llr": round(best, 3),
            "region_llr": params["region_llr"], "min_region_px": local.block, "g": round(local.g, 4),
            "tau": round(local.tau, 4),
            "regions": boxes, "grid": _grid(local, peak.rotation),
        }
        score = None if log10_lr is None else float(1.0 / (1.0 + 10.0 ** -log10_lr))
        if boxes:
            where = "; ".join(f"x {b[0]}-{b[2]}, y {b[1]}-{b[3]}" for b in boxes[:3])
            summary = (f"The reference camera's fingerprint is in the photo ({attribution}), but {len(boxes)} "
                       f"region(s) lack it where their content predicts it ({where}): their pixels did not come "
                       f"from this sensor, or were processed there.")
            headline = f"Fingerprint found (PCE {peak.pce:.3g}) but missing at {where.split(';')[0]}."
        else:
            summary = (f"The reference camera's fingerprint is in the photo ({attribution}), and no region of "
                       f"{local.block} px or more lacks it where its content predicts it "
                       f"({local.decidable.mean():.0%} of the blocks could be decided).")
            headline = f"Fingerprint found (PCE {peak.pce:.3g}); no region lacks it."
        return DetectorResult(Status.OK, summary, score=score, details=details, headline=headline, log10_lr=log10_lr)

    def localize(self, finding, shape: tuple[int, int]) -> np.ndarray | None:
        mask = np.zeros(shape, bool)
        for x0, y0, x1, y1 in (finding.details.get("local") or {}).get("regions", []):
            mask[y0:y1, x0:x1] = True
        return mask

    def report_section(self, finding, evidence):
        from .section import section

        return section(finding, evidence)


def _grid(local, rotation: int) -> dict[str, Any]:
    """The block log-likelihood ratios, rounded, for the report's map (turned back to the stored grid)."""
    llr = np.rot90(local.llr, k=-(rotation // 90))
    return {"llr": np.round(llr, 2).tolist(), "block": local.block, "step": local.step}
