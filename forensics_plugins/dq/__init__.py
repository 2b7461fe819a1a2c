"""Aligned double JPEG compression (dq): regions whose blocks do not carry the photo's earlier quantisation.

Pipeline: :mod:`.coefficients` (the stored luma DCT coefficients, read from
the file, and the calibrated estimate of their unquantised distribution) ->
:mod:`.primary` (per frequency, the earlier quantisation step that explains
the histogram) -> :mod:`.votes` (per 8 x 8 block, the log-likelihood ratio of
double against single quantisation) -> :mod:`.regions` (windows of blocks
that vote "single" more often than the rest of the photo does) ->
:mod:`.detector`.
"""
