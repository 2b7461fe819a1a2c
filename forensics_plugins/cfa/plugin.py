"""The cfa plugin (entry point ``cfa``): registers :class:`.detector.ColourFilterArray`; its module is imported only when the detectors are needed."""

from __future__ import annotations

from forensics_core import hookimpl


@hookimpl
def forensics_register_detectors(register):
    from .detector import ColourFilterArray

    register(ColourFilterArray())
