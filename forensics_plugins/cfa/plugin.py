"""Hook implementations of the cfa plugin (entry point ``cfa``)."""

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

    return analyse(evidence.pixels, params)


@hookimpl
def forensics_report_section(finding, evidence):
    if finding.name != NAME or not finding.details.get("thresholds"):
        return None
    from .section import report_section

    return report_section(finding, evidence)


@hookimpl
def forensics_localize(finding, shape):
    if finding.name != NAME:
        return None
    from .detector import regions_mask

    return regions_mask(finding.details, shape)


@hookimpl
def forensics_synthetic_cases(seed, count):
    from .synth import synthetic_cases

    return synthetic_cases(seed, count)
