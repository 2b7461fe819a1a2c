"""Lens radial distortion consistency (Chennamma & Rangarajan), as a forensics plugin.

Pipeline: :mod:`.edges` (sub-pixel edge points) -> :mod:`.lines` (distorted
straight lines) -> :mod:`.k1` (per-line distortion with uncertainty) ->
:mod:`.consistency` (global camera model and the splice test). The synthetic
photos for validation: :mod:`.scene` (what is photographed) -> :mod:`.render`
(through the lens) -> :mod:`.photo` (noise, resizing, JPEG; authentic photos)
-> :mod:`.splice` (the paper's three splices) -> :mod:`.truth` (truth records
and files) and :mod:`.cases` (the validation suite's cases).
"""
