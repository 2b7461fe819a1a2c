"""The object a plugin registers for each detector it provides.

A plugin subclasses :class:`Detector`, sets its :attr:`~Detector.spec`,
implements :meth:`~Detector.analyze` and, where it has them, the optional
methods, and registers an instance::

    from forensics_core import Detector, DetectorResult, DetectorSpec, Status, hookimpl

    class Brightness(Detector):
        spec = DetectorSpec("brightness", "1.0", "Mean brightness, as an example.")

        def analyze(self, evidence, params):
            mean = float(evidence.luma.mean())
            return DetectorResult(Status.OK, f"Mean luma {mean:.3f}.", details={"mean": mean})

    @hookimpl
    def forensics_register_detectors(register):
        register(Brightness())

The core keeps the objects and calls their methods: a method is only ever
called with this detector's findings, so no method needs to ask whether a
call is meant for it.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any, ClassVar

if TYPE_CHECKING:
    import numpy as np

    from .evidence import Evidence
    from .findings import DetectorFinding, DetectorResult, DetectorSpec
    from .reference import ReferenceSet
    from .report.sections import ReportSection
    from .synthetic import SyntheticCase


class Detector:
    """One detector: its declaration and the methods the core calls.

    Attributes
    ----------
    spec : DetectorSpec
        What the detector declares: its unique ``name``, the ``version`` of
        its implementation, ``description``, ``references``,
        ``default_params`` and optionally ``uses``, ``formats``,
        ``calibrated_on`` and ``supports_hd`` (see
        :class:`forensics_core.DetectorSpec`).

    Notes
    -----
    ``analyze`` and ``report_section`` run in a forked child process with a
    time limit, so they must not rely on state they change in the parent;
    ``localize`` and ``synthetic_cases`` run in the calling process. Every
    method must be deterministic for the same input and parameters (fix any
    random seed). A method that raises, hangs, crashes or returns something
    malformed costs only its own result, which the core records with the
    reason.
    """

    spec: ClassVar[DetectorSpec]

    def prepare(self) -> None:
        """Import what the methods need, in the main process, before the detector first runs (optional).

        Called once per process just before the detector's first
        ``analyze``, while other detectors may already run, so that the
        forked children share what it imports. The default does nothing;
        :class:`Deferred` imports its class here.
        """

    def analyze(self, evidence: Evidence, params: Mapping[str, Any]) -> DetectorResult:
        """Analyse one photo.

        Parameters
        ----------
        evidence : Evidence
            The stored pixel grid (``evidence.pixels``, ``(H, W)`` or
            ``(H, W, C)`` uint8, read-only; ``evidence.luma``, ``(H, W)``
            float in [0, 1]), the original bytes (``evidence.data``) and the
            recorded properties and EXIF (``evidence.info``). To decode the
            bytes again (a JPEG's own Y channel), use
            ``evidence.open_image()`` or decode inside ``with
            evidence.decoding():`` so the user's pixel limit applies.
        params : mapping
            The spec's ``default_params`` merged with the user's overrides.
        reference : ReferenceSet, optional
            Declare a parameter named ``reference``, and set the spec's
            ``uses_reference``, to receive the reference photos of the camera
            that allegedly took the photo (``forensics analyze --reference
            DIR``): each an :class:`~forensics_core.Evidence`, hashed and
            read-only as the evidence is; ``reference.digest`` names the set
            (a cache key). Without references the core records the detector
            ``skipped`` and does not call it.
        prior : mapping of str to DetectorFinding, optional
            Declare a parameter named ``prior`` to receive the
            findings of this run's detectors named in the spec's ``uses``
            (those that ran). Read another detector's details only through a
            record of :mod:`forensics_core.contracts` (e.g.
            ``RadialDistortion.from_finding``), and publish such a record
            with its ``to_details()``.

        Returns
        -------
        DetectorResult
            ``status`` (``ok``, ``inconclusive`` with the reason in the
            summary, or ``skipped``), a one-sentence ``summary``, a ``score``
            in [0, 1] (higher = more support for manipulation) or None, a
            ``p_value`` and/or ``nfa`` where the method defines one,
            JSON-serialisable ``details``, and a ``headline`` of at most 25
            words for the detector's row on the report's first page and in a
            batch's index. Raise on failure: the core records the exception
            as this detector's error.

        Notes
        -----
        Other detectors may run at the same time in their own children
        (``forensics analyze --jobs``), each limited to one BLAS thread;
        those named in ``uses`` have finished before this call starts.

        Evidential strength: the report states likelihood ratios, and your
        ``p_value`` (or ``nfa``) becomes one only once your detector is
        calibrated. Run ``forensics validate SUITE`` over photos of known
        origin with your detector and the others installed, then
        ``forensics calibrate validation.json --out cal.json``, and analyse
        with ``--calibration cal.json``. Until then your finding is shown
        with its p-value and score but kept out of the fused likelihood
        ratio (its LR reads "—").
        """
        raise NotImplementedError(f"{type(self).__name__} does not implement analyze")

    def report_section(self, finding: DetectorFinding, evidence: Evidence) -> ReportSection | None:
        """This detector's section of the evidence report (optional).

        Return a :class:`forensics_core.report.ReportSection`: a title, a
        Jinja2 template (autoescaped; never mark evidence-derived text safe),
        the context it renders with, figures (PNG or SVG bytes) it refers to
        by name, and tables (:class:`forensics_core.report.Table`) too long
        for a page, each written beside the report as
        ``<detector>-<key>.csv`` and listed in the signed manifest
        (``{{ tables.key }}`` says where in one line). Keep the section to
        about a page and at most two: what was measured on this photo, the
        key figure (``{{ figures.key.beside(mm) }}`` or ``.fit(mm)`` size
        it), a short table, method, limits and references. Return None (the
        default) for the core's generic section. Not called for a finding
        whose status is ``skipped``: the report gives its status and reason
        in one line.
        """
        return None

    def localize(self, finding: DetectorFinding, shape: tuple[int, int]) -> np.ndarray | None:
        """The map of the pixels this detector's ``finding`` flags (optional).

        Called by ``forensics validate`` to score localisation (MCC and IoU
        against true masks), and by the report for the outline it draws on
        page 1's photo when the finding drove the screen or its likelihood
        ratio supports manipulation. Return a boolean array of ``shape``
        ``(H, W)`` (the stored grid), True where the finding places
        manipulated content (all False when it found none), or None (the
        default) when the detector does not localise. Build it from
        ``finding.details`` alone; the photo is not passed.
        """
        return None

    def synthetic_cases(self, seed: int, count: int) -> Iterable[SyntheticCase]:
        """Photos with known ground truth that exercise this detector's trace (optional).

        Return (or yield) about ``count`` authentic and ``count`` spliced
        :class:`forensics_core.SyntheticCase` objects, built
        deterministically from ``seed``: the same seed must give the same
        bytes. Spread the cases over the conditions your detector's error
        rates depend on (JPEG quality, size, kind of splice) and tag them in
        ``conditions``. ``forensics validate synthetic`` runs every
        installed detector on every detector's cases. Keep each photo small
        enough (about 1-2 MP) for a suite of a few hundred photos to run in
        minutes. The default gives none.
        """
        return ()


class Deferred(Detector):
    """A detector registered by its spec now and its class later, imported the first time it is needed.

    A plugin whose code takes long to import registers
    ``Deferred(SPEC, "my_package.detector:MyDetector")`` instead of
    ``MyDetector()``: listing the plugins then imports only the spec, and the
    core imports the class in the main process just before the detector
    first runs, while other detectors already run, so that the forked
    children share the import. The class's own ``spec`` must equal ``spec``.

    Parameters
    ----------
    spec : DetectorSpec
        What the detector declares, as its class does.
    target : str
        ``"module:Class"``: where the class is; it is made with no arguments.
    """

    def __init__(self, spec: DetectorSpec, target: str):
        self.spec = spec
        self.target = target
        self._made: Detector | None = None

    def prepare(self) -> None:
        self.made()

    def made(self) -> Detector:
        """The detector itself, its module imported and its class made on the first call."""
        if self._made is None:
            module, _, name = self.target.partition(":")
            detector = getattr(importlib.import_module(module), name)()
            if not isinstance(detector, Detector) or detector.spec != self.spec:
                raise TypeError(f"{self.target} is not a Detector whose spec is the one registered for "
                                f"{self.spec.name!r}")
            self._made = detector
        return self._made

    def analyze(self, evidence: Evidence, params: Mapping[str, Any], prior: Mapping[str, DetectorFinding] | None = None,
                reference: ReferenceSet | None = None) -> DetectorResult:
        detector = self.made()
        extra: dict[str, Any] = {"reference": reference} if self.spec.uses_reference else {}
        if reads_prior(detector):
            extra["prior"] = prior or {}
        return detector.analyze(evidence, params, **extra)

    def report_section(self, finding: DetectorFinding, evidence: Evidence) -> ReportSection | None:
        return self.made().report_section(finding, evidence)

    def localize(self, finding: DetectorFinding, shape: tuple[int, int]) -> np.ndarray | None:
        return self.made().localize(finding, shape)

    def synthetic_cases(self, seed: int, count: int) -> Iterable[SyntheticCase]:
        return self.made().synthetic_cases(seed, count)


def implements(detector: Detector, method: str) -> bool:
    """Whether ``detector``'s class overrides :class:`Detector`'s ``method`` (the optional ones return nothing)."""
    if isinstance(detector, Deferred):
        detector = detector.made()
    return getattr(type(detector), method, None) is not getattr(Detector, method)


def reads_prior(detector: Detector) -> bool:
    """Whether ``detector.analyze`` declares the ``prior`` parameter (a deferred detector always passes it on)."""
    try:
        return "prior" in inspect.signature(detector.analyze).parameters
    except (TypeError, ValueError):
        return False
