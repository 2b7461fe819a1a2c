"""JPEG quantisation tables: standard IJG tables or the writer's own, and the quality.

libjpeg (the Independent JPEG Group's library, used by GIMP, Pillow and many
editors and phones) writes the example tables of ITU-T T.81 Annex K (tables
K.1 and K.2) scaled by the quality setting ``q`` (``jpeg_quality_scaling`` and
``jpeg_add_quant_table`` in libjpeg's ``jcparam.c``)::

    s = floor(5000 / q)   if q < 50
    s = 200 - 2 q         otherwise
    Q = clip(floor((K * s + 50) / 100), 1, 255)

Most camera firmware, and Photoshop, write their own tables (Farid 2006).
Tables equal to a scaled IJG pair therefore point to libjpeg-based software,
or to a compact or phone that uses libjpeg itself; that is an observation
about the last writer, not proof.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .checks import JPEG_FORMATS, Check

# T.81 Annex K, tables K.1 (luminance) and K.2 (chrominance), natural (row-major) order.
IJG_LUMA = np.array([
    16, 11, 10, 16, 24, 40, 51, 61,
    12, 12, 14, 19, 26, 58, 60, 55,
    14, 13, 16, 24, 40, 57, 69, 56,
    14, 17, 22, 29, 51, 87, 80, 62,
    18, 22, 37, 56, 68, 109, 103, 77,
    24, 35, 55, 64, 81, 104, 113, 92,
    49, 64, 78, 87, 103, 121, 120, 101,
    72, 92, 95, 98, 112, 100, 103, 99,
])
IJG_CHROMA = np.array([
    17, 18, 24, 47, 99, 99, 99, 99,
    18, 21, 26, 66, 99, 99, 99, 99,
    24, 26, 56, 99, 99, 99, 99, 99,
    47, 66, 99, 99, 99, 99, 99, 99,
] + [99] * 32)
QUALITIES = np.arange(1, 101)


def ijg_tables(quality: int | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The baseline IJG luminance and chrominance tables at ``quality``.

    Parameters
    ----------
    quality : int or ndarray of int, shape (Q,)
        libjpeg quality, 1 to 100.

    Returns
    -------
    luma, chroma : ndarray of int, shape (64,) or (Q, 64)
        Natural (row-major) order.
    """
    q = np.clip(np.asarray(quality), 1, 100)
    scale = np.where(q < 50, 5000 // q, 200 - 2 * q)[..., None]
    luma = np.clip((IJG_LUMA * scale + 50) // 100, 1, 255)
    chroma = np.clip((IJG_CHROMA * scale + 50) // 100, 1, 255)
    return luma, chroma


@dataclass(frozen=True)
class QuantisationEstimate:
    """How a file's tables compare with the scaled IJG tables.

    Attributes
    ----------
    n_tables : int
    standard_ijg : bool
        Every table equals the IJG table of its kind at one quality.
    quality : int
        The exact quality when ``standard_ijg``, else the nearest one.
    mean_abs_deviation : float
        Mean absolute difference, in quantisation steps, between the file's
        luminance table (and first chrominance table) and the IJG ones at
        ``quality``; 0 for an exact match.
    """

    n_tables: int
    standard_ijg: bool
    quality: int
    mean_abs_deviation: float


def estimate(tables: Mapping[str, Sequence[int]]) -> QuantisationEstimate | None:
    """Compare a file's quantisation tables with the IJG tables at every quality.

    Parameters
    ----------
    tables : mapping of str to sequence of int
        Table id to its 64 entries in natural order, as Pillow (>= 8.3) gives
        ``Image.quantization``. Table ``"0"`` is taken as luminance, the next
        ones as chrominance (the libjpeg and camera convention).

    Returns
    -------
    QuantisationEstimate or None
        None when there is no valid luminance table.
    """
    ordered = [np.asarray(tables[k]) for k in sorted(tables, key=lambda k: int(k) if str(k).isdigit() else 99)]
    ordered = [t for t in ordered if t.shape == (64,)]
    if not ordered:
        return None
    luma, chroma = ijg_tables(QUALITIES)
    dev = np.abs(luma - ordered[0]).mean(axis=1)
    if len(ordered) > 1:
        dev = (dev + np.abs(chroma - ordered[1]).mean(axis=1)) / 2
    exact = np.all(luma == ordered[0], axis=1)
    for table in ordered[1:]:
        exact &= np.all(chroma == table, axis=1)
    if exact.any():
        best = int(np.flatnonzero(exact)[-1])
        return QuantisationEstimate(len(ordered), True, int(QUALITIES[best]), 0.0)
    best = int(np.argmin(dev))
    return QuantisationEstimate(len(ordered), False, int(QUALITIES[best]), round(float(dev[best]), 3))


def quantisation_check(tables: Mapping[str, Sequence[int]], file_format: str, make: str | None,
                       own_table_makers: Sequence[str]) -> tuple[Check, QuantisationEstimate | None]:
    """The quantisation-table check.

    Standard IJG tables are common in compacts and phones that use libjpeg
    (in the test files: Casio, Nikon Coolpix, Jolla), so they are suspicious
    only when the EXIF names a maker whose cameras write their own tables
    (``own_table_makers``, e.g. Canon, Apple, Fujifilm): then the file was
    probably last saved by libjpeg-based software.

    Parameters
    ----------
    tables : mapping
        ``EvidenceInfo.quantization_tables``.
    file_format : str
        ``EvidenceInfo.format``.
    make : str or None
        EXIF Make.
    own_table_makers : sequence of str
        Lower-case words; a Make containing one names a maker that writes its own tables.
    """
    title = "JPEG quantisation tables"
    if file_format not in JPEG_FORMATS:
        return Check("quantisation", title, "not available", f"The file is {file_format}, not JPEG."), None
    est = estimate(tables)
    if est is None:
        return Check("quantisation", title, "not available", "The JPEG has no readable 8x8 quantisation table."), None
    own = make is not None and any(m in make.casefold() for m in own_table_makers)
    tables = "The only table is" if est.n_tables == 1 else f"The {est.n_tables} tables are"
    if est.standard_ijg:
        text = (f"{tables} the standard IJG {'one' if est.n_tables == 1 else 'ones'} at quality {est.quality}, as "
                "libjpeg-based software (GIMP, Pillow, many editors, some compacts and phones) writes")
        if own:
            return Check("quantisation", title, "suspicious",
                         text + f"; {make} cameras write their own tables, so the file was probably re-saved."), est
        return Check("quantisation", title, "note",
                     text + "; without the camera's own tables this cannot be told from an original."), est
    text = (f"{tables} not the standard IJG {'one' if est.n_tables == 1 else 'ones'} (nearest IJG quality "
            f"{est.quality}, mean deviation {est.mean_abs_deviation:.2f} steps): the writer used its own tables")
    if make is not None:
        return Check("quantisation", title, "consistent",
                     text + ", as camera firmware does (so do Photoshop and some other programs)."), est
    return Check("quantisation", title, "note",
                 text + " (cameras do, and so do Photoshop and some other programs)."), est
