"""The plugin module named by the entry point: it registers the detector, and imports it only then."""

from __future__ import annotations

from forensics_core import hookimpl


@hookimpl
def forensics_register_detectors(register):
    from .detector import NoiseLevel

    register(NoiseLevel())
