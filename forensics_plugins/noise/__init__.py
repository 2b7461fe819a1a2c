"""Noise-level inconsistency (noise): regions whose fine-grain noise differs from like content elsewhere.

Pipeline: :mod:`.blocks` (per 8 x 8 block: mean grey level, coarse texture
and fine-grain energy, from the block's DCT) -> :mod:`.residuals` (each
block's fine-grain energy against blocks of like grey level and texture in
the same photo) -> :mod:`.windows` (windows whose blocks are noisier or
smoother than the photo's own windows are) -> :mod:`.detector`.
"""
