"""The copy_move plugin (entry point ``copy_move``): registers :class:`.detector.CopyMove`; its module is imported only when the detectors are needed."""

from __future__ import annotations

from forensics_core import hookimpl


@hookimpl
def forensics_register_detectors(register):
    from .detector import CopyMove

    register(CopyMove())
