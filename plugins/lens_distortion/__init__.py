"""Lens radial distortion consistency (Chennamma & Rangarajan), as a forensics plugin.

Pipeline: :mod:`.edges` (sub-pixel edge points) -> :mod:`.lines` (distorted
straight lines) -> :mod:`.k1` (per-line distortion with uncertainty) ->
:mod:`.consistency` (global camera model and the splice test). :mod:`.synth`
renders synthetic authentic and spliced scenes for validation.
"""
