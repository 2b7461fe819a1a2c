"""The lens_distortion plugin (entry point ``lens_distortion``): registers :class:`.detector.LensDistortion`; its module is imported only when the detectors are needed."""

from __future__ import annotations

from forensics_core import hookimpl


@hookimpl
def forensics_register_detectors(register):
    from .detector import LensDistortion

    register(LensDistortion())


@hookimpl
def forensics_register_commands(cli):
    from .command import synth_command

    cli.add_command(synth_command, "synth")
