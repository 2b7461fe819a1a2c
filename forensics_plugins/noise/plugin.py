"""Hook implementations of the noise plugin (entry point ``noise``)."""

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
    if finding.name != NAME or "blocks" not in finding.details:
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
