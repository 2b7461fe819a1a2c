"""Metadata checks as a forensics plugin: what examiners look at first.

:mod:`.checks` (the check record; EXIF presence, Software, dates, dimensions),
:mod:`.thumbnail` (the IFD1 thumbnail against the image),
:mod:`.quantisation` (standard IJG tables and quality), :mod:`.lensdb`
(the EXIF lens in lensfun) -> :mod:`.conversion` (its distortion in the
project's convention) -> :mod:`.lens_check` (against the lens detector's
measurement); :mod:`.detector` assembles them, :mod:`.section` and
:mod:`.figures` make the report section.
"""
