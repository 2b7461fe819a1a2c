"""The metadata detector: the checks examiners run first, as one typed result.

Checks, in the report's order: EXIF present (:func:`.checks.exif_presence`),
Software tag and XMP creator tool (:func:`.checks.software_tag`,
:mod:`.xmp`), DateTime vs DateTimeOriginal (:func:`.checks.datetimes`), EXIF
pixel dimensions (:func:`.checks.dimensions`), embedded thumbnail
(:mod:`.thumbnail`), JPEG quantisation tables (:mod:`.quantisation`) and the
lens the EXIF names against the lens detector's measured distortion
(:mod:`.lens_check`). How often each calls an untouched camera original
suspicious is measured by ``benchmarks/metadata_real.py`` and quoted in the
report (:mod:`.real_rates`).

Metadata is never proof on its own and is not a statistical test here: the
result has no p-value and no NFA, so the fused verdict never rests on it. Its
score is the share of applicable checks (outcome consistent or suspicious)
that are suspicious.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from forensics_core import HEADLINE_WORDS, Detector, DetectorFinding, DetectorResult, Evidence, Status

from . import lens_check
from .checks import APPLICABLE, Check, datetimes, dimensions, dimensions_changed, exif_presence, software_tag
from .exiftool_checks import document_ancestors, embedded_previews, makernote_serial, xmp_dates
from .quantisation import quantisation_check
from .spec import LENS_DETECTOR, SPEC
from .thumbnail import ThumbnailThresholds, thumbnail_check
from .xmp import xmp_agents

if TYPE_CHECKING:
    from forensics_core.report import ReportSection


def thresholds(params: Mapping[str, Any]) -> ThumbnailThresholds:
    """The thumbnail check's limits from the detector's parameters.

    ``thumbnail_max_bytes`` and ``thumbnail_max_pixels`` apply to the
    thumbnail the intake read under its own limits (256 kB and 1,048,576
    pixels, their defaults): they can refuse what the intake accepted, not
    admit what it refused.
    """
    return ThumbnailThresholds(
        max_bytes=int(params["thumbnail_max_bytes"]),
        max_pixels=int(params["thumbnail_max_pixels"]),
        aspect_tolerance=float(params["thumbnail_aspect_tolerance"]),
        min_correlation=float(params["thumbnail_min_correlation"]),
        blur_px=float(params["thumbnail_blur_px"]),
        change_threshold=float(params["thumbnail_change_threshold"]),
        max_region_fraction=float(params["thumbnail_max_region_fraction"]),
    )


def _summary(checks: list[Check]) -> str:
    suspicious = [c.title for c in checks if c.outcome == "suspicious"]
    applicable = [c for c in checks if c.outcome in APPLICABLE]
    if not applicable:
        return ("Inconclusive: the file carries no metadata these checks can use, which says nothing either way "
                "about the photo.")
    if suspicious:
        return (f"{len(suspicious)} of {len(applicable)} applicable metadata checks are suspicious "
                f"({'; '.join(suspicious)}); metadata is never proof on its own.")
    return (f"All {len(applicable)} applicable metadata checks are consistent with a camera original; "
            "metadata is never proof on its own.")


def _headline(checks: list[Check]) -> str:
    """The finding in one sentence for page 1: which checks are suspicious, or that none is."""
    suspicious = [c.title for c in checks if c.outcome == "suspicious"]
    applicable = [c for c in checks if c.outcome in APPLICABLE]
    notes = sum(c.outcome == "note" for c in checks)
    if not applicable:
        return "Inconclusive: the file carries no metadata these checks can use."
    if not suspicious:
        noted = f" ({notes} note(s))" if notes else ""
        return (f"None of the {len(applicable)} applicable metadata checks is suspicious{noted}; metadata is never "
                f"proof on its own.")
    lead = f"{len(suspicious)} of {len(applicable)} applicable metadata checks suspicious"
    named = f"{lead}: {'; '.join(suspicious)}; metadata is never proof on its own."
    # Check titles are as long as their checks need; past the limit, the first one names the kind.
    if len(named.split()) <= HEADLINE_WORDS:
        return named
    return f"{lead}, first {suspicious[0]}; never proof on its own."


class Metadata(Detector):
    """What the file's own records say of its history: EXIF, MakerNotes, XMP, thumbnail and quantisation.

    References
    ----------
    .. [1] CIPA DC-008-2019 / JEITA CP-3451E, Exchangeable image file format
       for digital still cameras: Exif version 2.32, 2019.
    .. [2] E. Kee, M. K. Johnson, H. Farid, Digital image authentication from
       JPEG headers, IEEE Trans. Information Forensics and Security 6(3), 2011.
    .. [3] E. Kee, H. Farid, Digital image authentication from thumbnails,
       Proc. SPIE 7541, 2010.

    Examples
    --------
    >>> from forensics_core import load_evidence
    >>> from forensics_plugins.metadata.spec import DEFAULT_PARAMS
    >>> result = Metadata().analyze(load_evidence("tests/data/exif/87_OSError.jpg"), DEFAULT_PARAMS, prior={})
    >>> result.status.value, result.headline
    ('ok', '1 of 7 applicable metadata checks suspicious: Serial number: EXIF vs MakerNotes; metadata is never proof on its own.')
    """

    spec = SPEC

    def analyze(self, evidence: Evidence, params: Mapping[str, Any], prior: Mapping[str, DetectorFinding]) -> DetectorResult:
        """Run every metadata check on the evidence.

        Parameters
        ----------
        evidence : Evidence
            Read, never written: ``info`` (EXIF summary, format, size, quantisation
            tables), ``data`` (for XMP), ``thumbnail`` (the EXIF thumbnail as the
            intake read it) and ``pixels`` (to compare with it).
        params : mapping
            :data:`DEFAULT_PARAMS` with the user's overrides.
        prior : mapping
            Findings of this run; ``prior["lens_distortion"]`` when the lens detector ran.

        Returns
        -------
        DetectorResult
            ``ok`` with ``score`` = share of applicable checks that are suspicious
            and no p-value; ``inconclusive`` when no check applies.
        """
        info = evidence.info
        marks: dict[str, float] = {}
        t = time.perf_counter()
        checks = [exif_presence(info), software_tag(info, xmp_agents(evidence.data, evidence.decoding)),
                  datetimes(info, float(params["datetime_tolerance_s"])), dimensions(info),
                  xmp_dates(info, float(params["datetime_tolerance_s"])), document_ancestors(info), makernote_serial(info),
                  embedded_previews(info)]
        marks["tags"] = round(time.perf_counter() - t, 4)

        t = time.perf_counter()
        limits = thresholds(params)
        thumb, thumb_details = thumbnail_check(evidence.thumbnail, evidence.pixels, limits)
        checks.append(thumb)
        marks["thumbnail"] = round(time.perf_counter() - t, 4)

        t = time.perf_counter()
        quant, est = quantisation_check(info.quantization_tables, info.format, info.exif.make,
                                        [str(m).casefold() for m in params["own_table_makers"]])
        checks.append(quant)
        marks["quantisation"] = round(time.perf_counter() - t, 4)

        t = time.perf_counter()
        tol, alpha = float(params["lens_k1_tolerance"]), float(params["lens_alpha"])
        comparison = lens_check.compare(info, prior.get(LENS_DETECTOR), dimensions_changed(info),
                                        tol, alpha, int(params["lens_fit_grid"]))
        checks.append(lens_check.lens_check(comparison, tol, alpha))
        marks["lens"] = round(time.perf_counter() - t, 4)

        applicable = [c for c in checks if c.outcome in APPLICABLE]
        n_suspicious = sum(c.outcome == "suspicious" for c in checks)
        details = {
            "checks": [{"id": c.id, "title": c.title, "outcome": c.outcome, "observation": c.observation} for c in checks],
            "n_applicable": len(applicable),
            "n_suspicious": n_suspicious,
            "thumbnail": thumb_details,
            "quantisation": None if est is None else {
                "n_tables": est.n_tables, "standard_ijg": est.standard_ijg, "quality": est.quality,
                "mean_abs_deviation": est.mean_abs_deviation,
            },
            "lens": lens_check.details(comparison, tol, alpha),
            "image_size": [info.width, info.height],
            "elapsed_s": marks,
        }
        if not applicable:
            return DetectorResult(Status.INCONCLUSIVE, _summary(checks), details=details, headline=_headline(checks))
        return DetectorResult(Status.OK, _summary(checks), score=n_suspicious / len(applicable), details=details,
                              headline=_headline(checks))

    def report_section(self, finding: DetectorFinding, evidence: Evidence) -> ReportSection | None:
        from .section import report_section

        return report_section(finding, evidence) if finding.details.get("checks") else None
