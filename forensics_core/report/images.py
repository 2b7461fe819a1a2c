"""Images for the report: inline ``data:`` URLs at a resolution that keeps the PDF small.

Every image in the report is embedded, so ``report.html`` is self-contained
and the PDF renderer never fetches anything. Raster images are shown at
most :data:`MAX_SIDE` pixels on their longer side: enough for an A4 page at
about 200 dpi, and it keeps the PDF of a 12 MP photo around a megabyte.
Full-resolution figures are written beside the report as files.
"""

from __future__ import annotations

import base64
import io
import warnings

import numpy as np
from PIL import Image

from ..thumbnail import EmbeddedThumbnail
from .sections import Figure

MAX_SIDE = 1600
#: Raster figures up to this many pixels on their longer side (plots, small
#: maps) stay as given; larger ones (photos with overlays) are embedded as
#: JPEG, which keeps them readable at print resolution in a tenth of the bytes.
MAX_LOSSLESS_SIDE = 600
_JPEG_QUALITY = 85


_PNG_LEVEL = 1


def figure_png(img: Image.Image) -> bytes:
    """A plugin figure as PNG bytes, compressed fast.

    zlib's level 1 instead of Pillow's default 6: on a 1200-pixel map of a
    photo it takes 0.08 s instead of 0.41 s for 9 % more bytes. The figure
    is written once into the bundle and embedded in the PDF as JPEG anyway
    (:func:`for_report`).
    """
    buf = io.BytesIO()
    img.save(buf, format="PNG", compress_level=_PNG_LEVEL)
    return buf.getvalue()


def data_url(data: bytes, mime: str) -> str:
    return f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"


def _jpeg(img: Image.Image) -> bytes:
    buf = io.BytesIO()
    img.convert("RGB").save(buf, "JPEG", quality=_JPEG_QUALITY, optimize=True)
    return buf.getvalue()


def _to_8bit(pixels: np.ndarray) -> np.ndarray:
    """The stored grid as uint8 grey or RGB, for display only: values scaled by their type's range, NaN as 0."""
    px = pixels
    if px.ndim == 3:
        px = px[..., :3] if px.shape[2] >= 3 else px[..., 0]
    if px.dtype == np.uint8:
        return px
    scale = {"uint16": 65535.0, "int32": 65535.0}.get(px.dtype.name, 1.0)
    values = np.nan_to_num(np.asarray(px, dtype=np.float32), nan=0.0, posinf=scale, neginf=0.0)
    return np.clip(values / scale * 255.0 + 0.5, 0, 255).astype(np.uint8)


def display_image(pixels: np.ndarray, max_side: int, gain: float = 1.0, offset: float = 0.0) -> tuple[Image.Image, float]:
    """The photo as the background of a figure: RGB, at most ``max_side`` pixels long, and the factor it was reduced by.

    One rule for every figure and the report's preview: 8-bit grids as
    stored; 16-bit (and 32-bit integer) grids by their type's range, so that
    a dark 16-bit photo stays dark rather than being stretched to its own
    maximum; float grids as [0, 1]. Reducing comes first (Pillow's
    ``reducing_gap`` bins before resampling), so the cost does not grow with
    the photo's resolution; then each grey level v becomes ``gain * v +
    offset`` (e.g. 0.6 and 40 dim the photo so coloured marks stand out).

    Parameters
    ----------
    pixels : ndarray, shape (H, W) or (H, W, C)
        The stored grid (``evidence.pixels``).
    max_side : int
        Longest side of the result, pixels.
    gain, offset : float
        The tone mapping applied after reduction.

    Returns
    -------
    image : PIL.Image.Image
        RGB.
    factor : float
        Result size over stored size (1 when not reduced); multiply stored
        coordinates by it to draw on the image.

    Examples
    --------
    >>> import numpy as np
    >>> img, factor = display_image(np.full((300, 400), 1000, np.uint16), 200, gain=0.6, offset=40)
    >>> img.size, factor, img.getpixel((0, 0))
    ((200, 150), 0.5, (42, 42, 42))
    """
    img = Image.fromarray(_to_8bit(np.asarray(pixels)))
    full = max(img.size)
    img.thumbnail((max_side, max_side), Image.Resampling.LANCZOS, reducing_gap=2.0)
    rgb = img.convert("RGB")
    if gain != 1.0 or offset != 0.0:
        rgb = rgb.point([min(255, max(0, round(v * gain + offset))) for v in range(256)] * 3)
    return rgb, max(rgb.size) / full


def preview(pixels: np.ndarray, max_side: int = MAX_SIDE) -> bytes:
    """A JPEG of the stored grid (orientation not applied), at most ``max_side`` pixels long."""
    return _jpeg(display_image(pixels, max_side)[0])


def for_report(figure: Figure, max_side: int = MAX_SIDE) -> tuple[bytes, str]:
    """A plugin's figure as embedded in the report: large rasters as JPEG of at most ``max_side``, SVG as given.

    The figure itself is written beside the report at full resolution.

    Raises
    ------
    ValueError
        When the figure is not a PNG, JPEG or SVG, or does not decode.
    """
    if figure.mime == "image/svg+xml":
        return figure.data, figure.mime
    if figure.mime not in ("image/png", "image/jpeg"):
        raise ValueError(f"figure type {figure.mime!r} is not image/png, image/jpeg or image/svg+xml")
    with warnings.catch_warnings():
        warnings.simplefilter("error", Image.DecompressionBombWarning)
        with Image.open(io.BytesIO(figure.data), formats=["PNG", "JPEG"]) as img:
            if max(img.size) <= (max_side if figure.mime == "image/jpeg" else MAX_LOSSLESS_SIDE):
                img.verify()
                return figure.data, figure.mime
            img.load()
            img.thumbnail((max_side, max_side), Image.Resampling.LANCZOS, reducing_gap=2.0)
            return _jpeg(img), "image/jpeg"


def thumbnail_jpeg(thumbnail: EmbeddedThumbnail | None) -> bytes | None:
    """The evidence's EXIF thumbnail (``Evidence.thumbnail``) re-encoded as JPEG, or None when none decoded.

    The intake read it bounds-checked and decoded it under a pixel limit;
    only its re-encoded pixels reach the report, never the file's bytes.
    """
    img = None if thumbnail is None else thumbnail.image()
    return None if img is None else _jpeg(img)


WHERE_COLOURS = ("#d55e00", "#0072b2", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#f0e442", "#000000")
"""Outline colours of the Where figure, one per detector in report order (Okabe & Ito's palette, which readers
with the common colour-vision deficiencies tell apart); the stylesheet's ``swatch-N`` classes repeat them."""

WHERE_SIDE = 900
"""Longest side of the photo as the report shows it (page 1's Where, section 2), pixels: sharp at 150 mm wide."""


def where_figure(pixels: np.ndarray, masks: list[tuple[int, np.ndarray]], max_side: int = WHERE_SIDE) -> bytes:
    """The photo, dimmed, with each detector's flagged pixels outlined in its colour, as JPEG.

    Parameters
    ----------
    pixels : ndarray, shape (H, W) or (H, W, C)
        The stored grid (``evidence.pixels``).
    masks : list of (int, ndarray of bool, shape (H, W))
        Each flagging detector's index into :data:`WHERE_COLOURS` and its map
        (its ``localize``) at the stored size.
    max_side : int
        Longest side of the figure, pixels.

    Returns
    -------
    bytes
        A JPEG.

    Notes
    -----
    A map is box-averaged down to the figure's size, so that a flagged area
    smaller than one figure pixel still shows; its outline is the covered
    pixels with an uncovered neighbour, thickened to 5 pixels, so that it
    stays visible at print size.
    """
    from scipy import ndimage

    img, _ = display_image(pixels, max_side, gain=0.75, offset=20)
    rgb = np.asarray(img).copy()
    for index, mask in masks:
        cover = np.asarray(Image.fromarray(mask.astype(np.uint8) * 255).resize(img.size, Image.Resampling.BOX)) > 0
        if not cover.any():
            continue
        edge = cover & ~ndimage.binary_erosion(cover, border_value=0)
        edge = ndimage.binary_dilation(edge, iterations=2)
        colour = WHERE_COLOURS[index % len(WHERE_COLOURS)]
        rgb[edge] = [int(colour[i:i + 2], 16) for i in (1, 3, 5)]
    return _jpeg(Image.fromarray(rgb))
