"""The lens_distortion plugin (entry point ``lens_distortion``): :class:`.detector.LensDistortion`, imported when it first runs."""

from __future__ import annotations

from forensics_core import Deferred, hookimpl

from .spec import SPEC


@hookimpl
def forensics_register_detectors(register):
    register(Deferred(SPEC, f"{__package__}.detector:LensDistortion"))


@hookimpl
def forensics_register_commands(cli):
    from .command import synth_command

    cli.add_command(synth_command, "synth")
