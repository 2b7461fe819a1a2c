"""The luminance ZERO counts zeros on, taken as close as possible to what the decoder produced.

For a JPEG, the luminance channel is decoded directly (libjpeg asked for
YCbCr output through Pillow's ``draft``), so each pixel is the decoder's Y
value exactly: the inverse DCT of the quantised coefficients, rounded and
clipped. Recomputing Y from the decoded RGB would add the colour conversion's
rounding (up to a grey level, and more where RGB was clipped), which blurs
the zeros ZERO counts. Other formats (and JPEGs in other colour spaces, e.g.
CMYK) use the stored grid's BT.601 luma, rounded to integers as a JPEG
decoder's output is.
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np
from PIL import Image

from forensics_core import Evidence

# Formats whose image is JPEG-coded: an MPO (as phones and action cameras write, with a
# preview appended) holds its main image as an ordinary JPEG first.
JPEG_FORMATS = ("JPEG", "MPO")

# Below this side no 8x8 block has room to vote on all 64 grid origins and
# leave a meaningful count.
MIN_SIDE = 32


@dataclass(frozen=True)
class Luminance:
    """The analysed luminance and where it came from.

    Attributes
    ----------
    y : ndarray, shape (H, W), float32
        Grey levels 0-255, integer-valued.
    source : str
        ``"jpeg_y"`` (decoded Y channel), ``"jpeg_grey"`` (greyscale JPEG) or
        ``"luma"`` (rounded BT.601 luma of the stored pixels).
    note : str
        One sentence for the report on how ``y`` was obtained.
    table : ndarray, shape (8, 8), or None
        Luminance quantisation table of the file's (last) JPEG compression, in
        natural (row-major) order; None when the file is not a JPEG.
    jpeg : bool
        The file is a JPEG: every pixel went through its compression on the
        grid (0, 0).
    fine : ndarray, shape (H, W), float64, or None
        For a file stored losslessly, the luma before rounding (the lattice
        test reads coefficients to a fraction of a grey level); None for a
        JPEG, whose ``y`` is already exact.
    clipped : ndarray, shape (H, W), bool, or None
        Pixels with a colour channel at (for a JPEG: within a few grey levels
        of) the ends of its range, where clipping moved them off any
        quantisation lattice.
    """

    y: np.ndarray
    source: str
    note: str
    table: np.ndarray | None
    jpeg: bool = False
    fine: np.ndarray | None = None
    clipped: np.ndarray | None = None


def _decoded_y(evidence: Evidence) -> tuple[np.ndarray, str] | None:
    """The decoder's own Y (or grey) channel of a JPEG, or None when it cannot give one."""
    try:
        with evidence.decoding(), Image.open(io.BytesIO(evidence.data), formats=("JPEG",)) as img:
            if img.mode == "L":
                img.load()
                return np.asarray(img, dtype=np.float32), "jpeg_grey"
            if img.mode != "RGB":
                return None
            img.draft("YCbCr", img.size)
            if img.mode != "YCbCr":
                return None
            img.load()
            return np.asarray(img)[..., 0].astype(np.float32), "jpeg_y"
    except (OSError, SyntaxError, ValueError, EOFError, IndexError):
        return None


def _luma(evidence: Evidence) -> np.ndarray:
    return np.round(np.clip(evidence.luma, 0.0, 1.0) * 255.0).astype(np.float32)


# A JPEG decoder clips each colour channel to 0-255; a later compression's
# ringing moves clipped pixels a few grey levels back inside.
_JPEG_CLIP_MARGIN = 3


def _clipped(evidence: Evidence, margin: int) -> np.ndarray | None:
    px = evidence.pixels
    if px.dtype != np.uint8:
        return None
    if px.ndim == 3:
        px = px[..., :3]
        return ((px <= margin) | (px >= 255 - margin)).any(axis=2)
    return (px <= margin) | (px >= 255 - margin)


def luminance(evidence: Evidence) -> Luminance:
    """The luminance to analyse and the file's luminance quantisation table.

    Parameters
    ----------
    evidence : Evidence
        Read only; for a JPEG its bytes are decoded again into Y.

    Returns
    -------
    Luminance
    """
    table = None
    raw = evidence.info.quantization_tables.get("0")
    if evidence.info.format in JPEG_FORMATS and raw is not None and len(raw) == 64:
        table = np.asarray(raw, dtype=np.float64).reshape(8, 8)
    if evidence.info.format in JPEG_FORMATS:
        decoded = _decoded_y(evidence)
        if decoded is not None and decoded[0].shape == evidence.pixels.shape[:2]:
            y, source = decoded
            note = ("the JPEG's luminance channel exactly as decoded (no colour conversion)"
                    if source == "jpeg_y" else "the greyscale JPEG's decoded channel")
            return Luminance(y=y, source=source, note=note, table=table, jpeg=True,
                             clipped=_clipped(evidence, _JPEG_CLIP_MARGIN))
        return Luminance(y=_luma(evidence), source="luma", table=table, jpeg=True,
                         note="the BT.601 luma of the decoded pixels, rounded (the JPEG's Y channel was not available)")
    fine = np.clip(evidence.luma, 0.0, 1.0) * 255.0 if evidence.pixels.dtype == np.uint8 else None
    return Luminance(y=_luma(evidence), source="luma", table=None, fine=fine, clipped=_clipped(evidence, 0),
                     note="the BT.601 luma of the stored pixels, rounded to grey levels")
