"""What one detector's findings publish for another detector to read.

A detector that declares ``uses=("other",)`` receives the other detector's
finding in ``prior`` (see :meth:`forensics_core.Detector.analyze`). What it may read from that
finding's ``details`` is fixed here, as a typed record with one reader, so
that a change on the publishing side is a change of this contract, not a
silent break of the reading side.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from .findings import DetectorFinding, Status

#: The key under which a finding's ``details`` carry its :class:`RadialDistortion`.
RADIAL_DISTORTION_KEY = "global_model"
_UNITS = "normalised: image centre at 0, half the larger side = 1; cx_px, cy_px in pixels from the centre"


@dataclass(frozen=True)
class RadialDistortion:
    """A camera's radial lens distortion as measured on one photo (division model, Devernay & Faugeras 2001).

    Published by the ``lens_distortion`` detector under
    ``details["global_model"]``; read by the ``metadata`` detector to compare
    it with the lens the EXIF names.

    Attributes
    ----------
    k1, k2 : float
        Radial coefficients, in normalised coordinates (image centre 0, half
        the larger side 1); k1 > 0 is barrel distortion.
    k1_stderr, k2_stderr : float
        Their standard errors, model error included. ``k2 = 0`` with
        ``k2_stderr = 0`` states a one-term model (the paper's), ``k2``
        held at zero: compare ``k1`` with another source's one-term ``k1``.
    cx, cy, cx_stderr, cy_stderr : float
        Centre of distortion and its standard errors, normalised.
    cx_px, cy_px : float
        The centre in pixels from the image centre.
    sigma_px : float
        Median residual of the lines about the model, pixels.
    n_lines_explained, n_lines_informative : int
        Lines the model explains, of those informative about k1.

    References
    ----------
    .. [1] F. Devernay, O. Faugeras, Straight lines have to be straight,
       Machine Vision and Applications 13, 2001.

    Examples
    --------
    A detector that ``uses=("lens_distortion",)`` reads it from ``prior``:

    >>> def analyze(self, evidence, params, prior):
    ...     lens = RadialDistortion.from_finding(prior.get("lens_distortion"))
    ...     if lens is None:
    ...         ...  # say what could not be compared
    """

    k1: float
    k1_stderr: float
    k2: float
    k2_stderr: float
    cx: float
    cx_stderr: float
    cy: float
    cy_stderr: float
    cx_px: float
    cy_px: float
    sigma_px: float
    n_lines_explained: int
    n_lines_informative: int

    def to_details(self) -> dict[str, Any]:
        """The JSON form stored in the publishing finding's details."""
        return {**asdict(self), "units": _UNITS}

    @classmethod
    def from_finding(cls, finding: DetectorFinding | None) -> RadialDistortion | None:
        """The measurement a finding stood by: None unless its status is ``ok`` and it carries a complete record."""
        if finding is None or finding.status is not Status.OK or not isinstance(finding.details, Mapping):
            return None
        record = finding.details.get(RADIAL_DISTORTION_KEY)
        if not isinstance(record, Mapping):
            return None
        try:
            values = {name: record[name] for name in cls.__dataclass_fields__}
        except KeyError:
            return None
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values.values()):
            return None
        return cls(**values)


#: The key under which a finding's ``details`` name global processing the photo shows (:class:`Processing`).
PROCESSING_KEY = "processing"


@dataclass(frozen=True)
class Processing:
    """Global processing a detector recognised in the photo: nothing inserted, moved or removed.

    Published under ``details["processing"]``; the report states it on its
    first page, beside the verdict, so that an examiner reads processing
    (lens correction, resizing, recompression) as processing and not as a
    trace of manipulation.

    Attributes
    ----------
    kind : str
        A short name, e.g. ``"radial resampling"``.
    description : str
        What was done, completing "The photo was ...", e.g. ``"resampled by
        a radial warp about its centre after a first JPEG compression, as
        lens correction does"``.
    """

    kind: str
    description: str

    def to_details(self) -> dict[str, Any]:
        """The JSON form stored in the publishing finding's details (a detector may add its evidence beside it)."""
        return asdict(self)

    @classmethod
    def from_finding(cls, finding: DetectorFinding | None) -> Processing | None:
        """The processing a finding stood by: None unless its status is ``ok`` and it names one."""
        if finding is None or finding.status is not Status.OK or not isinstance(finding.details, Mapping):
            return None
        record = finding.details.get(PROCESSING_KEY)
        if not isinstance(record, Mapping) or not all(isinstance(record.get(k), str) for k in ("kind", "description")):
            return None
        return cls(kind=record["kind"], description=record["description"])


#: Inside a finding's processing record, the key of its :class:`RadialResampling`.
RADIAL_RESAMPLING_KEY = "radial"


@dataclass(frozen=True)
class RadialResampling:
    """A radial warp of the whole photo about its centre, after its first compression: lens correction.

    Published by the ``jpeg_grid`` detector inside its processing record
    (``details["processing"]["radial"]``, key ``profile_terms_px``), where
    the first compression's grid shows the warp; read by the ``cfa``
    detector, whose mosaic the same warp moves. The content now at distance
    ``r`` from the centre ``((W - 1) / 2, (H - 1) / 2)`` of the stored grid
    was moved along its radius by

    ``D(r) = a (r / R)^3 + b (r / R)`` pixels (outwards when positive),

    ``R`` the half diagonal: the one-term radial model of the paper's eqs.
    1-5 with the zoom an editor adds to fill the frame.

    Attributes
    ----------
    a, b : float
        The profile's terms, pixels.

    References
    ----------
    .. [1] H. R. Chennamma, L. Rangarajan, Image splicing detection using
       inherent lens radial distortion, IJCSI 7(6), 2010 (the radial model).
    """

    a: float
    b: float

    def displacement(self, y: np.ndarray, x: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """``(dy, dx)``, pixels: how far the content now at pixel rows ``y``, columns ``x`` was moved.

        ``y`` and ``x`` broadcast together; ``shape`` is the stored grid's
        ``(H, W)``.
        """
        cy, cx = (shape[0] - 1) / 2.0, (shape[1] - 1) / 2.0
        vy, vx = np.asarray(y, dtype=np.float64) - cy, np.asarray(x, dtype=np.float64) - cx
        r = np.maximum(np.hypot(vy, vx), 1e-9)
        rho = r / float(np.hypot(cy, cx))
        along = (self.a * rho**3 + self.b * rho) / r
        return along * vy, along * vx

    def to_details(self) -> dict[str, Any]:
        """The JSON form inside the publishing finding's processing record (beside the publisher's evidence)."""
        return {"profile_terms_px": [self.a, self.b]}

    @classmethod
    def from_finding(cls, finding: DetectorFinding | None) -> RadialResampling | None:
        """The warp a finding stood by: None unless it names processing (:class:`Processing`) with a complete warp."""
        if Processing.from_finding(finding) is None:
            return None
        record = finding.details[PROCESSING_KEY].get(RADIAL_RESAMPLING_KEY)
        terms = record.get("profile_terms_px") if isinstance(record, Mapping) else None
        if (not isinstance(terms, (list, tuple)) or len(terms) != 2
                or not all(isinstance(t, (int, float)) and not isinstance(t, bool) and np.isfinite(t) for t in terms)):
            return None
        return cls(float(terms[0]), float(terms[1]))


#: The key under which a finding's ``details`` carry a source statement (:class:`SourceAttribution`).
ATTRIBUTION_KEY = "attribution"


@dataclass(frozen=True)
class SourceAttribution:
    """A likelihood ratio for the photo's source, for propositions of its own, kept apart from the manipulation
    statement.

    Published under ``details["attribution"]`` by a detector that compares
    the photo with a claimed camera (``prnu``); the report states it on its
    first page in a line of its own, never in the fused likelihood ratio,
    which answers whether content was inserted, moved or removed.

    Attributes
    ----------
    hp, hd : str
        The source propositions, e.g. "the photo was taken by the reference
        camera" and "by another camera of the same model".
    log10_lr : float
        Calibrated and bounded.
    basis : str
        What the LR rests on, completing "Based on ...", e.g. "the PCE of the
        sensor fingerprint (1.2e4)".
    """

    hp: str
    hd: str
    log10_lr: float
    basis: str

    def to_details(self) -> dict[str, Any]:
        """The JSON form stored in the publishing finding's details."""
        return asdict(self)

    @classmethod
    def from_finding(cls, finding: DetectorFinding | None) -> SourceAttribution | None:
        """The source statement of a finding that ran (``ok`` or ``inconclusive``); None without a complete one."""
        if (finding is None or finding.status not in (Status.OK, Status.INCONCLUSIVE)
                or not isinstance(finding.details, Mapping)):
            return None
        record = finding.details.get(ATTRIBUTION_KEY)
        if not isinstance(record, Mapping) or not all(isinstance(record.get(k), str) for k in ("hp", "hd", "basis")):
            return None
        value = record.get("log10_lr")
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            return None
        return cls(hp=record["hp"], hd=record["hd"], log10_lr=float(value), basis=record["basis"])
