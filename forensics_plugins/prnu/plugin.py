"""The prnu plugin (entry point ``prnu``): :class:`.detector.Prnu`, imported when it first runs."""

from __future__ import annotations

from forensics_core import Deferred, hookimpl

from .spec import SPEC


@hookimpl
def forensics_register_detectors(register):
    register(Deferred(SPEC, f"{__package__}.detector:Prnu"))
