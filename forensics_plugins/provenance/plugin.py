"""Hook implementations of the provenance plugin (entry point ``provenance``)."""

from __future__ import annotations

import importlib

from forensics_core import hookimpl

from .spec import NAME, SPEC


@hookimpl
def forensics_register_detectors():
    return [SPEC]


@hookimpl
def forensics_prepare():
    importlib.import_module(f"{__package__}.detector")


@hookimpl
def forensics_analyze(detector, evidence, params):
    if detector != NAME:
        return None
    from .detector import analyse

    return analyse(evidence, params)


@hookimpl
def forensics_report_section(finding, evidence):
    if finding.name != NAME or "credentials" not in finding.details:
        return None
    from .section import report_section

    return report_section(finding, evidence)
