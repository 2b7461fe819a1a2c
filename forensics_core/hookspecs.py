"""The plugin contract: the hooks a plugin may implement.

A plugin is a module (or object) listed under the entry-point group
``forensics.plugins`` of its distribution::

    [project.entry-points."forensics.plugins"]
    my_detector = "my_package.plugin"

and decorates its functions with :data:`forensics_core.hookimpl`. A plugin
implements only the hooks it needs; argument names must match the
specifications below, and a plugin may accept fewer arguments than offered.

Detectors are objects: a plugin registers a :class:`forensics_core.Detector`
for each through :func:`forensics_register_detectors`, and the core calls
that object's methods. The other hooks are plugin-wide, and pluggy calls
them (``pm.hook.<name>``), so its ordering (``tryfirst``, ``trylast``) and
``firstresult`` hold. An implementation that raises is recorded as that
plugin's failure and left out of the call, which then goes on without it:
one broken plugin never takes the others down.

A plugin written for plugin API 1 (``forensics_analyze``,
``forensics_report_section``, ``forensics_localize``,
``forensics_synthetic_cases``, ``forensics_prepare``, and
``forensics_register_detectors`` returning a list of specs) fails to load,
with a message naming the method of :class:`~forensics_core.Detector` that
replaced the hook.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import pluggy

if TYPE_CHECKING:
    import click

    from .detector import Detector
    from .evidence import Evidence
    from .findings import DetectorFinding, Verdict

PROJECT = "forensics"

hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)
"""Decorator for a plugin's hook implementations (exported as ``forensics_core.hookimpl``)."""

REPLACED_HOOKS = {
    "forensics_analyze": "Detector.analyze",
    "forensics_report_section": "Detector.report_section",
    "forensics_localize": "Detector.localize",
    "forensics_synthetic_cases": "Detector.synthetic_cases",
    "forensics_prepare": "Detector.prepare",
}
"""Hooks of plugin API 1 and what replaced each in API 2 (named in a load error)."""


@hookspec
def forensics_register_detectors(register: Callable[[Detector], None]) -> None:
    """Register the detectors this plugin provides: call ``register(detector)`` for each.

    ``detector`` is an instance of a :class:`forensics_core.Detector`
    subclass, whose docstrings are the contract of the methods the core
    calls. Detector names must be unique across all installed plugins; a
    clash, a spec that is not valid or an exception here is reported as a
    load error of this plugin, whose detectors are then all left out.

    The core calls this hook once, in the main process, the first time it
    needs the detectors (not for ``forensics --help`` or a plugin's own
    commands), before any photo is analysed. Keep it quick: a detector
    whose code takes long to import is registered as
    ``Deferred(SPEC, "my_package.detector:MyDetector")``
    (:class:`forensics_core.Deferred`), so that ``forensics plugins`` reads
    only its spec and the core imports the class just before it first runs,
    in the main process, while other detectors already run; the forked
    children then share the import.
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
    ``evidence.data`` holds its bytes. Each plugin's implementation runs in
    a forked child with the run's time limit, so that its answer can be
    recorded under its name and a hang costs only that answer.
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

    The first implementation to return a verdict decides (``firstresult``):
    pluggy calls the last-registered plugin first, so a plugin may take over
    a built-in policy by implementing it; mark the implementation
    ``@hookimpl(trylast=True)`` to be asked only after the others.
    """


@hookspec
def forensics_register_commands(cli: click.Group) -> None:
    """Add click commands to the ``forensics`` command line.

    Use ``@cli.command()`` on your functions; choose names that will not
    clash with the core's (``analyze``, ``plugins``) or other plugins'.
    """
