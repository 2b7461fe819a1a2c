"""Hook implementations of the metadata plugin (entry point ``metadata``)."""

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
def forensics_analyze(detector, evidence, params, prior):
    if detector != NAME:
        return None
    from .detector import analyse

    return analyse(evidence, params, prior)


@hookimpl
def forensics_report_section(finding, evidence):
    if finding.name != NAME or not finding.details.get("checks"):
        return None
    from .section import report_section

    return report_section(finding, evidence)
