"""The noise plugin (entry point ``noise``): registers :class:`.detector.NoiseLevel`; its module is imported only when the detectors are needed."""

from __future__ import annotations

from forensics_core import hookimpl


@hookimpl
def forensics_register_detectors(register):
    from .detector import NoiseLevel

    register(NoiseLevel())
