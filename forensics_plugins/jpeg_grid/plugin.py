"""The jpeg_grid plugin (entry point ``jpeg_grid``): registers :class:`.detector.JpegGrid`; its module is imported only when the detectors are needed."""

from __future__ import annotations

from forensics_core import hookimpl


@hookimpl
def forensics_register_detectors(register):
    from .detector import JpegGrid

    register(JpegGrid())
