"""The provenance plugin (entry point ``provenance``): registers :class:`.detector.Provenance`; its module is imported only when the detectors are needed."""

from __future__ import annotations

from forensics_core import hookimpl


@hookimpl
def forensics_register_detectors(register):
    from .detector import Provenance

    register(Provenance())
