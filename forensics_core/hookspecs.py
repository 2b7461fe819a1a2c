"""The plugin contract: every hook a detector plugin may implement.

A plugin is a module (or object) listed under the entry-point group
``forensics.plugins`` of its distribution::

    [project.entry-points."forensics.plugins"]
    my_detector = "my_package.plugin"

and decorates its functions with :data:`forensics_core.hookimpl`. A plugin
implements only the hooks it needs; argument names must match the
specifications below, and a plugin may accept fewer arguments than offered.

The core calls each plugin's implementation on its own, so a plugin that
raises, hangs or returns something malformed is recorded as failed and never
takes the others down.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import pluggy

if TYPE_CHECKING:
    import click
    import numpy as np

    from .evidence import Evidence
    from .findings import DetectorFinding, DetectorResult, DetectorSpec, Verdict
    from .report.sections import ReportSection
    from .synthetic import SyntheticCase

PROJECT = "forensics"

hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)
"""Decorator for a plugin's hook implementations (exported as ``forensics_core.hookimpl``)."""


@hookspec
def forensics_register_detectors() -> Sequence[DetectorSpec]:
    """Declare the detectors this plugin provides.

    Return a list of :class:`forensics_core.DetectorSpec`: for each, a unique
    ``name`` (lower case, digits and underscores), the implementation's
    ``version``, a one-sentence ``description``, the ``references`` it follows
    and its ``default_params``; optionally the other detectors it ``uses``,
    the evidence ``formats`` it applies to (those its null model was
    checked on; the core records ``skipped`` with the reason on any other,
    without calling the plugin) and ``calibrated_on="score"`` for a detector
    that states no test but a measured statistic, whose likelihood ratio is
    then calibrated on its ``score``, and ``supports_hd=False`` for a
    detector that looks for one kind of manipulation only, so that its clean
    finding is never read as support for an original. Detector names must be unique across all
    installed plugins; a clash is reported as a load error of the later plugin.
    """


@hookspec
def forensics_prepare() -> None:
    """Import the code your detectors run, once, before photos are analysed.

    Called once in the main process (and once per worker process of a
    batch), just before the first of your detectors starts, while other
    plugins' detectors may already be running. Each ``forensics_analyze``
    call runs in a forked child: modules imported here are shared with every
    child, while a module first imported inside ``forensics_analyze`` is
    imported again for every photo.

    Keep the plugin module itself light, importing at module level only what
    ``forensics_register_detectors`` needs (your ``DetectorSpec``), so that
    ``forensics plugins`` and ``forensics --help`` start in a fraction of a
    second; import the numerical code here, e.g.
    ``importlib.import_module(__package__ + ".detector")``. Like the import
    of your plugin module, this runs in the main process: do nothing here
    but import. A failure is ignored; the detector then fails in its own
    child, where it is recorded.
    """


@hookspec
def forensics_analyze(
    detector: str, evidence: Evidence, params: Mapping[str, Any], prior: Mapping[str, DetectorFinding]
) -> DetectorResult | None:
    """Analyse one photo with one of this plugin's detectors.

    Called once per photo for each selected detector, only on the plugin that
    registered ``detector``. ``evidence`` gives the stored pixel grid
    (``evidence.pixels``, read-only; ``evidence.luma`` as float in [0, 1]),
    the original bytes (``evidence.data``) and the recorded properties and
    EXIF (``evidence.info``). To decode the bytes again (a JPEG's own Y
    channel), use ``evidence.open_image()`` or decode inside
    ``with evidence.decoding():`` so the user's pixel limit applies. ``params`` holds the detector's default
    parameters merged with the user's overrides. ``prior`` maps the names in
    the spec's ``uses`` to their findings in this run, for those that ran
    (declare the argument only if you need it; it is empty otherwise). Read
    another detector's details only through a record of
    :mod:`forensics_core.contracts` (e.g. ``RadialDistortion.from_finding``),
    and publish such a record with its ``to_details()``.

    Return a :class:`forensics_core.DetectorResult`: ``status`` (``ok``,
    ``inconclusive`` with the reason in the summary, or ``skipped``), a
    one-sentence ``summary``, a ``score`` in [0, 1] (higher = more support for
    manipulation) or None, a ``p_value`` and/or ``nfa`` where the method
    defines one, JSON-serialisable ``details``, and a ``headline`` of at most
    25 words for your row on the report's first page and in a batch's
    index ("Regions at x 1380-1625 carry another JPEG grid (NFA 10^-6.7).";
    without one, the summary's first sentence is cut to 25 words). Raise on
    failure: the core records the exception as this detector's error.

    The call runs in a child process with a time limit (``--timeout``), so it
    must not rely on state it changes in the parent; it must be deterministic
    for the same input and parameters (fix any random seed). Other detectors
    may run at the same time in their own children (``forensics analyze
    --jobs``), each limited to one BLAS thread; those named in ``uses`` have
    finished before this call starts.

    Evidential strength: the report states likelihood ratios, and your
    ``p_value`` (or ``nfa``) becomes one only once your detector is
    calibrated. Run ``forensics validate SUITE`` over photos of known origin
    with your detector and the others installed, then ``forensics calibrate
    validation.json --out cal.json``, and analyse with ``--calibration
    cal.json``. Until then your finding is shown with its p-value and score
    but kept out of the fused likelihood ratio (its LR reads "—").
    """


@hookspec
def forensics_report_section(finding: DetectorFinding, evidence: Evidence) -> ReportSection | None:
    """Contribute this plugin's section of the evidence report.

    Called for each finding whose detector this plugin registered (the plugin
    may ignore findings of other detectors by returning None). Return a
    :class:`forensics_core.report.ReportSection`: a title, a Jinja2 template
    (autoescaped; never mark evidence-derived text safe), the context it
    renders with, figures (PNG or SVG bytes) it refers to by name, and
    tables (:class:`forensics_core.report.Table`) too long for a page, each
    written beside the report as ``<detector>-<key>.csv`` and listed in the
    signed manifest (``{{ tables.key }}`` says where in one line). Keep the
    section to about a page and at most two: what was measured on this
    photo, the key figure (``{{ figures.key.beside(mm) }}`` or
    ``.fit(mm)`` size it), a short table, method, limits and references.
    """


@hookspec
def forensics_extract_metadata(evidence: Evidence) -> Mapping[str, Any] | None:
    """Optionally read extra metadata from the evidence.

    The core already records every tag ExifTool reads (EXIF, MakerNotes, XMP,
    IPTC, ICC, JUMBF) in ``evidence.info.metadata`` (a list of
    :class:`forensics_core.MetadataTag`: ``group``, ``name``, ``value``) and
    names the reader in ``evidence.info.metadata_reader``; read them there.
    Implement this hook for what ExifTool does not read or does not group
    the way your detector needs.

    Return a JSON-serialisable mapping; it is recorded in the findings under
    ``evidence.extra_metadata[<plugin name>]``. Do not re-open the file:
    ``evidence.data`` holds its bytes.
    """


@hookspec(firstresult=True)
def forensics_fuse(policy: str, findings: Sequence[DetectorFinding], evidence: Evidence) -> Verdict | None:
    """Combine the detectors' findings into the verdict, under ``policy``.

    ``policy`` is the name the user chose (``--fusion``; default
    ``bonferroni``, built in). Return None unless ``policy`` names the rule
    this plugin implements; otherwise return a :class:`forensics_core.Verdict`
    whose ``explanation`` states the rule, its threshold and which detectors
    drove the outcome. Inconclusive, skipped and failed detectors must count
    for neither side.
    """


@hookspec
def forensics_register_commands(cli: click.Group) -> None:
    """Add click commands to the ``forensics`` command line.

    Use ``@cli.command()`` on your functions; choose names that will not
    clash with the core's (``analyze``, ``plugins``) or other plugins'.
    """


@hookspec
def forensics_synthetic_cases(seed: int, count: int) -> Iterable[SyntheticCase]:
    """Generate photos with known ground truth that exercise this plugin's trace.

    Return (or yield) about ``count`` authentic and ``count`` spliced
    :class:`forensics_core.SyntheticCase` objects, built deterministically
    from ``seed``: the same seed must give the same bytes. Spread the cases
    over the conditions your detector's error rates depend on (JPEG quality,
    size, kind of splice) and tag them in ``conditions``. ``forensics
    validate synthetic`` runs every installed detector on every plugin's
    cases. Keep each photo small enough (about 1-2 MP) for a suite of a few
    hundred photos to run in minutes.
    """


@hookspec
def forensics_localize(finding: DetectorFinding, shape: tuple[int, int]) -> np.ndarray | None:
    """Turn one of this plugin's findings into a map of the pixels it flags.

    Called by ``forensics validate`` to score localisation (MCC and IoU
    against true masks), and by the report for the outline it draws on page
    1's photo when your finding drove the screen or its likelihood ratio
    supports manipulation; only on the plugin whose detector made ``finding``.
    Return a boolean array of ``shape`` ``(H, W)`` (the stored grid), True
    where the finding places manipulated content (all False when it found
    none), or None when the detector does not localise or ``finding`` is not
    yours. Build it from ``finding.details`` alone; the photo is not passed.
    """
