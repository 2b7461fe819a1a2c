"""Typed findings: what a detector returns and what ``findings.json`` records.

The dataclasses here are the one model of a run. They become JSON only at the
edge (:func:`Findings.to_json`), and that JSON is described by
``forensics_core/schema/findings.schema.json``, which the tests validate
against. Bump :data:`SCHEMA_VERSION` whenever a field changes meaning.
"""

from __future__ import annotations

import enum
import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields
from typing import Any

SCHEMA_VERSION = "1.7"


class Status(str, enum.Enum):
    """Outcome of one detector on one photo.

    ``ok``: the detector ran and its numbers speak (for or against manipulation).
    ``inconclusive``: it ran but the photo does not carry enough of its trace
    (e.g. too few straight lines); never to be read as "authentic".
    ``error``: it failed; ``error`` says why. ``skipped``: it did not apply.
    """

    OK = "ok"
    INCONCLUSIVE = "inconclusive"
    ERROR = "error"
    SKIPPED = "skipped"


class VerdictLabel(str, enum.Enum):
    """The three outcomes an examiner may state."""

    INCONSISTENT = "inconsistent"
    CONSISTENT = "consistent"
    INCONCLUSIVE = "inconclusive"


class MalformedResult(ValueError):
    """A plugin returned something that is not a valid :class:`DetectorResult`."""


@dataclass(frozen=True)
class DetectorSpec:
    """What a plugin declares about one detector it provides.

    Parameters
    ----------
    name : str
        Unique detector name, ``[a-z][a-z0-9_]*`` (used on the command line).
    version : str
        Version of the method's implementation; recorded in every finding.
    description : str
        One sentence for ``forensics plugins`` and the report.
    references : tuple of str
        Literature the method follows, one citation per item.
    default_params : mapping
        JSON-serialisable parameters and their defaults; a user may override
        any of them, and the merged set is recorded with the finding.
    uses : tuple of str
        Other detectors whose findings this one reads (``prior`` in
        ``Detector.analyze``). When both are selected, those run first; when
        one is absent or fails, this detector still runs and must say what
        it could not compare.
    formats : tuple of str
        Evidence formats (``EvidenceInfo.format``: ``JPEG``, ``MPO``, ``PNG``,
        ``TIFF``, ``WEBP``, ``HEIF``, ``AVIF``) the detector applies to, i.e.
        those its null model was checked on; empty for all. On any other
        format the core does not call it and records it ``skipped`` with the
        reason.
    calibrated_on : str
        What a likelihood-ratio calibrator reads from the detector's findings:
        ``"p_value"`` (its p-value, or ``min(1, nfa)``; the default) or
        ``"score"``, for a detector that states no test but a measured
        statistic (such a detector is advisory to the p-value triage rules).
    supports_hd : bool
        Whether the detector's findings can support Hd ("as the camera
        produced it"); true by default. False for a detector whose clean
        finding must not be weighed against the manipulations it cannot see
        (one validated on its own kind of manipulation only, with no data on
        the others Hp covers): its calibrated LR is then never below 1.
    uses_reference : bool
        Whether the detector compares the evidence with reference photos of
        the camera that allegedly took it (``forensics analyze --reference
        DIR``). The core passes them as ``reference``
        (:class:`forensics_core.ReferenceSet`) to ``Detector.analyze``, and
        records the detector ``skipped`` when none were given.
    """

    name: str
    version: str
    description: str
    references: tuple[str, ...] = ()
    default_params: Mapping[str, Any] = field(default_factory=dict)
    uses: tuple[str, ...] = ()
    formats: tuple[str, ...] = ()
    calibrated_on: str = "p_value"
    supports_hd: bool = True
    uses_reference: bool = False


HEADLINE_WORDS = 25
"""The most words of a finding's headline (:attr:`DetectorResult.headline`)."""


@dataclass
class DetectorResult:
    """What a detector's ``analyze`` returns for one photo.

    Parameters
    ----------
    status : Status
        See :class:`Status`.
    summary : str
        One sentence a reader of the report understands.
    score : float or None
        In [0, 1]; higher means more support for manipulation. ``None`` when the
        detector has no opinion (inconclusive, skipped).
    p_value : float or None
        Probability, under the stated null hypothesis "the photo is an
        original", of evidence at least this strong, where the method defines one.
    nfa : float or None
        Number of false alarms (a-contrario methods), where defined.
    details : dict
        Method-specific, JSON-serialisable numbers (numpy scalars and arrays are
        converted; NaN and infinities are refused: use ``None``).
    headline : str or None
        The finding in one sentence of at most :data:`HEADLINE_WORDS` words,
        for the detector's row on the report's first page and the batch
        index ("Regions at x 1380-1625 carry another JPEG grid (NFA
        10^-6.7)."). Where it is missing or longer, the report shows the
        summary's first sentence, cut to that length.
    log10_lr : float or None
        The detector's own calibrated log10 likelihood ratio for the
        manipulation propositions, for a detector calibrated on data that
        ``forensics validate`` records cannot hold (reference photos of a
        claimed camera); say in ``details["calibration"]`` what it was
        fitted on. The core uses it instead of any calibrator of its own for
        the detector, and adds it to the fused LR as a trace independent of
        the others'. None for the usual detector, which the core calibrates.
    """

    status: Status
    summary: str
    score: float | None = None
    p_value: float | None = None
    nfa: float | None = None
    details: dict[str, Any] = field(default_factory=dict)
    headline: str | None = None
    log10_lr: float | None = None


@dataclass(kw_only=True)
class DetectorFinding:
    """One detector's entry in ``findings.json``: its result plus provenance (built by keyword).

    ``output`` keeps what the detector's process printed (its stdout and
    stderr, libraries' warnings included), cut at 4,000 characters, instead
    of letting it reach the user's terminal.
    """

    name: str
    version: str
    plugin: str
    status: Status
    summary: str
    score: float | None
    p_value: float | None
    nfa: float | None
    details: dict[str, Any]
    parameters: dict[str, Any]
    elapsed_s: float
    error: str | None = None
    log10_lr: float | None = None
    output: str | None = None
    headline: str | None = None


class Role(str, enum.Enum):
    """What one detector's finding did in the fused verdict.

    ``drove``: its test decided the outcome. ``counted``: its test entered the
    combination without deciding it. ``advisory``: it ran and reports
    observations but no test (e.g. metadata), so it counts for neither side.
    ``not counted``: inconclusive, skipped or failed.
    """

    DROVE = "drove"
    COUNTED = "counted"
    ADVISORY = "advisory"
    NOT_COUNTED = "not counted"


@dataclass
class Contribution:
    """One detector's part in the verdict.

    ``p_value`` is the p-value the policy took from the finding (its p-value,
    or ``min(1, NFA)``); ``adjusted_p`` the same after the policy's correction
    for several tests, where it has one.
    """

    detector: str
    role: Role
    p_value: float | None = None
    adjusted_p: float | None = None


@dataclass
class Verdict:
    """The fused outcome and how it was reached.

    ``p_value`` is the single number the decision rests on (for example the
    smallest Bonferroni-adjusted p-value, or Fisher's combined p-value) and
    ``alpha`` the level, fixed in advance, it is compared with; both are None
    when no test ran or the policy defines none. ``method`` states the rule.
    """

    label: VerdictLabel
    score: float | None
    explanation: str
    policy: str
    drivers: list[str] = field(default_factory=list)
    p_value: float | None = None
    alpha: float | None = None
    method: str = ""
    contributions: list[Contribution] = field(default_factory=list)
    log10_lr: float | None = None
    likelihood_ratio: LikelihoodRatio | None = None


@dataclass
class LikelihoodRatio:
    """The evaluative statement: how much more probable the findings are under Hp than under Hd.

    ``log10_lr`` is the fused log10 likelihood ratio from calibrators fitted
    on validation data (:mod:`forensics_core.calibration`), None when no
    calibrator applies. ``contributed`` names the detectors whose own LR is
    not 1 and enter the fusion; ``uncalibrated`` those that ran without a
    calibrator (shown, kept out of the LR); ``experimental`` those with a
    calibrator that the fusion leaves out because they carried no
    information on real photos (their own LR shown, not fused). ``calibration`` identifies the calibrators and their data;
    ``relevance`` says in one sentence how far that data resembles this photo.
    """

    hp: str
    hd: str
    log10_lr: float | None
    verbal: str
    contributed: list[str] = field(default_factory=list)
    uncalibrated: list[str] = field(default_factory=list)
    calibration: dict[str, Any] = field(default_factory=dict)
    relevance: str = ""
    experimental: list[str] = field(default_factory=list)


@dataclass
class GpsPosition:
    """GPS position in decimal degrees (WGS-84 as EXIF records it) and metres."""

    latitude: float | None
    longitude: float | None
    altitude_m: float | None


@dataclass
class RawTag:
    """One EXIF tag exactly as stored, its value rendered as safe text."""

    ifd: str
    tag: int
    name: str
    value: str


@dataclass
class MetadataTag:
    """One tag as ExifTool reads it: its family-1 group (``IFD0``, ``ExifIFD``, ``Canon``, ``XMP-xmpMM``,
    ``IPTC``, ``ICC_Profile``, ``JUMBF``, ...), its name and its value rendered as safe text."""

    group: str
    name: str
    value: str


@dataclass
class ExifSummary:
    """The EXIF fields examiners read first, plus every tag in ``raw``; ``unreadable`` says why EXIF could not be
    parsed (the photo is still analysed)."""

    make: str | None = None
    model: str | None = None
    lens_make: str | None = None
    lens_model: str | None = None
    focal_length_mm: float | None = None
    focal_length_35mm: float | None = None
    datetime: str | None = None
    datetime_original: str | None = None
    software: str | None = None
    orientation: int | None = None
    exif_image_width: int | None = None
    exif_image_height: int | None = None
    gps: GpsPosition | None = None
    thumbnail_present: bool = False
    raw: list[RawTag] = field(default_factory=list)
    unreadable: str | None = None


@dataclass
class ContainedImage:
    """An image in the evidence container besides the one analysed.

    ``kind`` names what the container says it is (``frame``, ``page``, ``MPO
    large thumbnail``, ``HEIF thumbnail``, ``HEIF depth image`` …);
    ``index`` is its position in the container (frames and pages) or among
    the primary image's auxiliary images.
    """

    index: int
    kind: str
    width: int | None = None
    height: int | None = None


@dataclass
class EvidenceInfo:
    """Identity and properties of the evidence file, taken before any analysis.

    ``width`` and ``height`` are those of the stored pixel grid; ``orientation``
    is reported, never applied. In a container with several images the
    primary one is analysed and the others are listed in ``other_images``;
    ``decoder_note`` says what the decoder did that the stored bytes do not
    (e.g. a HEIF rotation property that libheif always applies).
    ``metadata`` holds every tag ExifTool read, by group, and
    ``metadata_reader`` names the reader and its arguments, or says why
    Pillow's EXIF reading (``exif.raw``) is all there is.
    ``changed_during_analysis`` is set when the file on disk no longer had
    the hashed bytes after the detectors ran (a plugin or another program
    wrote to it): the findings are then of the bytes as hashed, and the
    evidence must be secured again.
    """

    path: str
    name: str
    size: int
    sha256: str
    sha512: str
    md5: str
    hashed_at: str
    format: str
    width: int
    height: int
    mode: str
    orientation: int | None
    icc_profile: bool
    quantization_tables: dict[str, list[int]]
    exif: ExifSummary
    extra_metadata: dict[str, Any] = field(default_factory=dict)
    other_images: list[ContainedImage] = field(default_factory=list)
    decoder_note: str | None = None
    metadata: list[MetadataTag] = field(default_factory=list)
    metadata_reader: str | None = None
    changed_during_analysis: str | None = None


@dataclass
class PluginRecord:
    """How one plugin loaded: listed in ``forensics plugins`` and in findings."""

    name: str
    distribution: str | None
    version: str | None
    status: str
    hooks: list[str] = field(default_factory=list)
    detectors: list[str] = field(default_factory=list)
    error: str | None = None


@dataclass
class ReferenceRecord:
    """A reference photo of the claimed camera, as the findings list it (:mod:`forensics_core.reference`)."""

    name: str
    size: int
    sha256: str
    format: str
    width: int
    height: int


@dataclass
class Tool:
    name: str
    version: str


@dataclass
class Findings:
    """Everything one analysis established about one photo."""

    schema_version: str
    tool: Tool
    created: str
    evidence: EvidenceInfo
    parameters: dict[str, Any]
    environment: dict[str, Any]
    plugins: list[PluginRecord]
    detectors: list[DetectorFinding]
    verdict: Verdict
    references: list[ReferenceRecord] = field(default_factory=list)
    """Reference photos given with ``--reference`` (empty without)."""

    def to_dict(self) -> dict[str, Any]:
        return asdict(self, dict_factory=_enum_values)

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2, ensure_ascii=False, allow_nan=False) + "\n"

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Findings:
        """Rebuild findings read back from ``findings.json``."""
        ev = dict(data["evidence"])
        exif = dict(ev["exif"])
        exif["gps"] = GpsPosition(**exif["gps"]) if exif.get("gps") else None
        exif["raw"] = [RawTag(**t) for t in exif.get("raw", [])]
        ev["exif"] = ExifSummary(**exif)
        ev["other_images"] = [ContainedImage(**c) for c in ev.get("other_images", [])]
        ev["metadata"] = [MetadataTag(**t) for t in ev.get("metadata", [])]
        verdict = dict(data["verdict"])
        verdict["label"] = VerdictLabel(verdict["label"])
        verdict["contributions"] = [
            Contribution(**{**c, "role": Role(c["role"])}) for c in verdict.get("contributions", [])
        ]
        if verdict.get("likelihood_ratio"):
            verdict["likelihood_ratio"] = LikelihoodRatio(**verdict["likelihood_ratio"])
        return cls(
            schema_version=data["schema_version"],
            tool=Tool(**data["tool"]),
            created=data["created"],
            evidence=EvidenceInfo(**ev),
            parameters=dict(data["parameters"]),
            environment=dict(data["environment"]),
            plugins=[PluginRecord(**p) for p in data["plugins"]],
            detectors=[
                DetectorFinding(**{**d, "status": Status(d["status"])}) for d in data["detectors"]
            ],
            verdict=Verdict(**verdict),
            references=[ReferenceRecord(**r) for r in data.get("references", [])],
        )


def _enum_values(items: list[tuple[str, Any]]) -> dict[str, Any]:
    return {k: (v.value if isinstance(v, enum.Enum) else v) for k, v in items}


def to_jsonable(value: Any, where: str = "details") -> Any:
    """Return ``value`` as plain JSON types, converting numpy scalars and arrays.

    Raises
    ------
    MalformedResult
        On NaN, infinities, or a type JSON cannot hold; the message names the
        offending key path so a plugin author can find it.
    """
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise MalformedResult(f"{where} is {value}; use None for a missing number")
        return value
    if isinstance(value, Mapping):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise MalformedResult(f"{where} has a non-string key {k!r}")
            out[k] = to_jsonable(v, f"{where}.{k}")
        return out
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v, f"{where}[{i}]") for i, v in enumerate(value)]
    tolist = getattr(value, "tolist", None)
    if callable(tolist) and type(value).__module__ == "numpy":
        return to_jsonable(tolist(), where)
    if hasattr(value, "__dataclass_fields__"):
        return to_jsonable({f.name: getattr(value, f.name) for f in fields(value)}, where)
    raise MalformedResult(f"{where} has a value of type {type(value).__name__}, which JSON cannot hold")


def _unit_or_none(value: Any, name: str) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) and type(value).__module__ != "numpy":
        raise MalformedResult(f"{name} must be a number or None, not {type(value).__name__}")
    try:
        number = float(value)
    except (TypeError, ValueError) as exc:
        raise MalformedResult(f"{name} must be a number or None") from exc
    if not math.isfinite(number):
        raise MalformedResult(f"{name} is {number}; use None")
    return number


def check_result(result: Any) -> DetectorResult:
    """Validate what a plugin returned and normalise it to plain JSON values.

    Raises
    ------
    MalformedResult
        With a message that says what is wrong.
    """
    if not isinstance(result, DetectorResult):
        raise MalformedResult(f"expected a DetectorResult, got {type(result).__name__}")
    try:
        status = Status(result.status)
    except ValueError as exc:
        raise MalformedResult(f"unknown status {result.status!r}") from exc
    if not isinstance(result.summary, str) or not result.summary.strip():
        raise MalformedResult("summary must be a non-empty sentence")
    score = _unit_or_none(result.score, "score")
    p_value = _unit_or_none(result.p_value, "p_value")
    nfa = _unit_or_none(result.nfa, "nfa")
    if score is not None and not 0.0 <= score <= 1.0:
        raise MalformedResult(f"score {score} is outside [0, 1]")
    if p_value is not None and not 0.0 <= p_value <= 1.0:
        raise MalformedResult(f"p_value {p_value} is outside [0, 1]")
    if nfa is not None and nfa < 0.0:
        raise MalformedResult(f"nfa {nfa} is negative")
    if not isinstance(result.details, Mapping):
        raise MalformedResult("details must be a mapping")
    if result.headline is not None and not isinstance(result.headline, str):
        raise MalformedResult("headline must be a sentence or None")
    log10_lr = None
    if result.log10_lr is not None:
        if isinstance(result.log10_lr, bool) or not isinstance(result.log10_lr, (int, float)) \
                or not math.isfinite(float(result.log10_lr)):
            raise MalformedResult("log10_lr must be a finite number or None")
        log10_lr = float(result.log10_lr)
    return DetectorResult(
        status=status,
        summary=result.summary.strip(),
        score=score,
        p_value=p_value,
        nfa=nfa,
        details=to_jsonable(result.details),
        headline=result.headline.strip() or None if result.headline is not None else None,
        log10_lr=log10_lr,
    )


def schema() -> dict[str, Any]:
    """The JSON Schema that every ``findings.json`` satisfies."""
    from importlib.resources import files

    return json.loads(files("forensics_core").joinpath("schema/findings.schema.json").read_text(encoding="utf-8"))
