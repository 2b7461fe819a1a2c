"""Hook implementations of the provenance plugin (entry point ``provenance``)."""

from __future__ import annotations

from forensics_core import hookimpl

from .detector import NAME, SPEC, analyse


@hookimpl
def forensics_register_detectors():
    return [SPEC]


@hookimpl
def forensics_analyze(detector, evidence, params):
    if detector != NAME:
        return None
    return analyse(evidence, params)


@hookimpl
def forensics_report_section(finding, evidence):
    if finding.name != NAME or "credentials" not in finding.details:
        return None
    from .section import report_section

    return report_section(finding, evidence)
