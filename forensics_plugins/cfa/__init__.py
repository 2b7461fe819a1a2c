"""Colour-filter-array demosaicing consistency, as a forensics plugin (entry point ``cfa``).

Pipeline: :mod:`.residuals` (per-block prediction residuals at the four
positions of the 2 x 2 Bayer cell) -> :mod:`.votes` (the photo's own
signature and each block's vote for a shift of the mosaic) -> :mod:`.naming`
(the Bayer pattern's name, by demosaicing again) -> :mod:`.regions`
(a-contrario regions whose phase disagrees). :mod:`.bayer` and
:mod:`.demosaic` model the camera; :mod:`.synth` renders raw-like authentic and
spliced photos for validation.
"""
