"""The embedded EXIF thumbnail (IFD1) against the stored image.

A camera writes a small JPEG of the picture into the EXIF block (IFD1, tags
JPEGInterchangeFormat 0x0201 and JPEGInterchangeFormatLength 0x0202, offsets
counted from the TIFF header; Exif 2.32). Many editors change the pixels but
copy the EXIF block unchanged, so the thumbnail keeps showing the picture as
it was: a thumbnail that does not match the image is a classic sign of
editing (Kee & Farid 2010 study thumbnails as forensic evidence; editors
that do regenerate the thumbnail leave one that matches, which this check
cannot tell from the camera's).

The intake reads and decodes the thumbnail once, bounds-checked and under
its own size and pixel limits (``Evidence.thumbnail``, a
:class:`forensics_core.EmbeddedThumbnail`); the check's own limits
``thumbnail_max_bytes`` and ``thumbnail_max_pixels`` apply on top of those.
Stages here: locate the thumbnail's picture area (cameras letterbox a 3:2
picture into a 4:3 thumbnail with black bands; :func:`content_box`), find the
part of the image it shows and compare the two through a fitted tone curve
(:func:`compare`). Neither the thumbnail nor the image has the orientation
tag applied: both are stored in the sensor's frame.

What real cameras do, measured on 58 camera originals of about 50 models:
the Nikon D70/D70s/D200 letterbox a 3:2 picture into 160 x 120 (the D70 with
bands on all four sides and a thumbnail about 4 % narrower than the image),
the Kodak DC280 puts its band on one side only, the Olympus E-10 crops 7 % on
every side, and every camera renders the thumbnail with its own tone curve
and sharpening. After the alignment and tone fit all 58 match with
correlation above 0.99 and no differing region above 0.12 % of the picture.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from PIL import Image
from scipy import ndimage, optimize
from scipy.optimize import isotonic_regression

from forensics_core import EmbeddedThumbnail

from .checks import Check

# Bands a camera fills to letterbox the picture: nearly uniform (luma standard
# deviation below this, on a [0, 1] scale) once the row or column next to the
# picture, which JPEG ringing touches, is left out.
_BAND_MAX_STD = 0.04
_BAND_MIN_PX = 2
# How far the thumbnail's picture may be cropped from (inset) or reach past
# (outset) the image on each side, as a fraction of the image: camera crops
# measured on real originals reach 7 %; one thumbnail line is about 1 %.
_MAX_INSET, _MAX_OUTSET = 0.12, 0.02
_SIMPLEX_STEP = 0.03
_OVERSAMPLE = 4
_WORK_PX = 192
_EDGE_PX = 2
_TONE_BINS = 256


@dataclass(frozen=True)
class Comparison:
    """The thumbnail against the image reduced to its picture area.

    Attributes
    ----------
    box : tuple of int
        Picture area in the thumbnail, ``(x0, y0, x1, y1)`` pixels, end exclusive.
    aspect_image, aspect_thumbnail : float
        Width / height of the stored image and of the thumbnail's picture area.
    aspect_difference : float
        ``|ln(aspect_thumbnail / aspect_image)|``.
    aspect_tolerance : float
        Allowed ``aspect_difference``: the parameter plus the rounding of a
        picture area this small (1.5 px on its shorter side).
    rotated : bool
        The thumbnail's aspect matches the image turned by 90 degrees instead.
    correlation : float or None
        Pearson correlation of the two blurred lumas (None when either is flat or too small).
    correlation_outside : float or None
        The same outside the largest differing region (and its blur margin):
        high when the rest of the picture matches, i.e. the difference is local.
    image_rect : tuple of float or None
        The part of the image the picture area shows, ``(x0, y0, x1, y1)`` as
        fractions of the image's width and height (``(0, 0, 1, 1)``: all of it).
    psnr_db : float or None
        PSNR of the thumbnail against the image through the fitted tone curve, dB.
    changed_fraction : float or None
        Share of the picture area whose residual exceeds the change threshold.
    region_fraction : float or None
        Share of the picture area covered by the largest connected changed region.
    changed_box : tuple of int or None
        Bounding box, thumbnail pixels (end exclusive), of the largest changed region.
    difference : ndarray or None, shape (h, w)
        Absolute residual of the blurred lumas, luma units; for the report's figure.
    """

    box: tuple[int, int, int, int]
    aspect_image: float
    aspect_thumbnail: float
    aspect_difference: float
    aspect_tolerance: float
    rotated: bool
    image_rect: tuple[float, float, float, float] | None = None
    correlation: float | None = None
    correlation_outside: float | None = None
    psnr_db: float | None = None
    changed_fraction: float | None = None
    region_fraction: float | None = None
    changed_box: tuple[int, int, int, int] | None = None
    difference: np.ndarray | None = None


def luma_of(img: Image.Image) -> np.ndarray:
    """BT.601 luma of an RGB or grey Pillow image, float in [0, 1], shape (h, w)."""
    return np.asarray(img.convert("L"), dtype=np.float64) / 255.0


def to_8bit(pixels: np.ndarray) -> np.ndarray:
    """The stored grid as 8-bit grey or RGB, shape (H, W) or (H, W, 3); alpha dropped, 16-bit and float scaled."""
    px = np.asarray(pixels)
    if px.ndim == 3:
        px = px[..., :3] if px.shape[2] >= 3 else px[..., 0]
    if px.dtype == np.uint8:
        return px
    scale = {"uint16": 65535.0, "int32": 65535.0}.get(px.dtype.name, 1.0)
    return np.clip(px.astype(np.float32) / scale * 255.0 + 0.5, 0, 255).astype(np.uint8)


def reduced_image(pixels: np.ndarray, size: tuple[int, int]) -> Image.Image:
    """The stored grid reduced to ``size`` = (w, h), as 8-bit RGB or grey.

    Pillow bins by an integer factor first (``reducing_gap``), so a 12 MP
    photo costs tens of milliseconds, then resamples with Lanczos.
    """
    return Image.fromarray(to_8bit(pixels)).resize(size, Image.Resampling.LANCZOS, reducing_gap=3.0)


def _band_width(mean: np.ndarray, std: np.ndarray) -> int:
    """How many leading lines form a uniform band, given each line's luma mean and standard deviation, shape (n,)."""
    uniform = (std < _BAND_MAX_STD) & (np.abs(mean - mean[0]) < _BAND_MAX_STD)
    return int(uniform.size if uniform.all() else np.argmin(uniform))


def content_box(thumb: np.ndarray, aspect_image: float) -> tuple[int, int, int, int]:
    """The thumbnail's picture area: all of it, or the part inside uniform bands.

    Cameras letterbox or pillarbox a picture whose aspect differs from the
    thumbnail's fixed frame (a 3:2 photo in 160 x 120, the Nikon D70 even on
    all four sides, the Kodak DC280 on one side only). Each side's band is
    the run of uniform lines (standard deviation and departure from the
    outermost line below ``_BAND_MAX_STD``) of at least ``_BAND_MIN_PX``
    lines, plus the line next to the picture, which the thumbnail's JPEG
    ringing and resampling mix with the band. Of the whole thumbnail and the
    areas inside the row bands, the column bands or both, the one whose
    aspect is nearest the image's is the picture: a uniform sky or wall
    therefore is not taken for a band unless removing it makes the framing
    fit.

    Parameters
    ----------
    thumb : ndarray, shape (h, w)
        Thumbnail luma in [0, 1].
    aspect_image : float
        Width / height of the stored image.

    Returns
    -------
    tuple of int
        ``(x0, y0, x1, y1)``, end exclusive.
    """
    h, w = thumb.shape
    rows_mean, rows_std, cols_mean, cols_std = thumb.mean(1), thumb.std(1), thumb.mean(0), thumb.std(0)
    top, bottom = _band_width(rows_mean, rows_std), _band_width(rows_mean[::-1], rows_std[::-1])
    left, right = _band_width(cols_mean, cols_std), _band_width(cols_mean[::-1], cols_std[::-1])
    top, bottom, left, right = (n + 1 if n >= _BAND_MIN_PX else 0 for n in (top, bottom, left, right))
    # A portrait picture pillarboxed in a landscape frame leaves about 40 % of
    # the width; a band is accepted while at least a quarter remains.
    rows = (0, top, w, h - bottom) if (top or bottom) and top + bottom < 0.75 * h else None
    cols = (left, 0, w - right, h) if (left or right) and left + right < 0.75 * w else None
    both = (left, top, w - right, h - bottom) if rows and cols else None
    candidates = [b for b in ((0, 0, w, h), rows, cols, both) if b is not None]
    return min(candidates, key=lambda b: abs(math.log((b[2] - b[0]) / (b[3] - b[1]) / aspect_image)))


def monotone_fit(x: np.ndarray, y: np.ndarray, n_bins: int = _TONE_BINS) -> np.ndarray:
    """Least-squares non-decreasing tone curve ``y ~ f(x)``, evaluated at ``x``.

    The samples are pooled into up to ``n_bins`` bins of equal count along
    ``x``; the bin means are made non-decreasing by pool-adjacent-violators
    (scipy's ``isotonic_regression``, weighted by bin size) and interpolated
    linearly.

    Parameters
    ----------
    x, y : ndarray, shape (n,)
        Image and thumbnail luma.
    n_bins : int

    Returns
    -------
    ndarray, shape (n,)
        ``f(x)``.

    References
    ----------
    M. Ayer, H. D. Brunk, G. M. Ewing, W. T. Reid, E. Silverman, An empirical distribution function for sampling
    with incomplete information, Ann. Math. Statist. 26(4), 641-647, 1955 (pool-adjacent-violators).
    """
    order = np.argsort(x, kind="stable")
    xs, ys = x[order], y[order]
    n = min(n_bins, x.size)
    starts = (np.arange(n) * x.size) // n
    weights = np.diff(np.append(starts, x.size)).astype(np.float64)
    centres = np.add.reduceat(xs, starts) / weights
    levels = np.add.reduceat(ys, starts) / weights
    fitted = isotonic_regression(levels, weights=weights, increasing=True).x
    return np.interp(x, centres, fitted)


def _sample(image: np.ndarray, rect: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """``image`` resampled (bilinear) on a ``shape`` grid covering ``rect`` = (x0, x1, y0, y1), image fractions."""
    h, w = shape
    ih, iw = image.shape
    xs = (rect[0] + (np.arange(w) + 0.5) / w * (rect[1] - rect[0])) * iw - 0.5
    ys = (rect[2] + (np.arange(h) + 0.5) / h * (rect[3] - rect[2])) * ih - 0.5
    yy, xx = np.meshgrid(ys, xs, indexing="ij")
    return ndimage.map_coordinates(image, [yy, xx], order=1, mode="nearest")


def _align(t: np.ndarray, image: np.ndarray, blur_px: float) -> tuple[np.ndarray, np.ndarray]:
    """The part of the image the thumbnail's picture area shows, and the image resampled onto it.

    Cameras make the thumbnail from their own rendering: some crop it a few
    per cent (the Olympus E-10 by 7 % on each side, the Nikon D70 by 4 % on
    the right and 5 % at the bottom), some squeeze it into a fixed frame, and
    a band found one line off shifts it by a pixel. The rectangle of the
    image, in fractions ``(x0, x1, y0, y1)``, that maximises the correlation
    with the thumbnail is found by Nelder-Mead from the whole image, each edge
    bounded to ``_MAX_INSET`` inside and ``_MAX_OUTSET`` outside it. A local
    edit cannot move four edges, so it stays in the residual; a crop of the
    image after capture needs an edge outside the bounds and shows there.

    Parameters
    ----------
    t : ndarray, shape (h, w)
        Blurred thumbnail picture area.
    image : ndarray, shape (H, W)
        Image luma, low-pass filtered for sampling at the thumbnail's pitch.
    blur_px : float
        The Gaussian applied to ``t``, thumbnail pixels.

    Returns
    -------
    rect : ndarray, shape (4,)
    resampled : ndarray, shape (h, w)
        The image over ``rect``, blurred like ``t``.

    References
    ----------
    J. A. Nelder, R. Mead, A simplex method for function minimization, The Computer Journal 7(4), 308-313, 1965.
    """
    full = np.array([0.0, 1.0, 0.0, 1.0])

    def resampled(rect: np.ndarray) -> np.ndarray:
        return ndimage.gaussian_filter(_sample(image, rect, t.shape), blur_px, mode="nearest")

    def cost(rect: np.ndarray) -> float:
        m = resampled(rect)
        return 1.0 if m.std() < 1e-9 else -float(np.corrcoef(t.ravel(), m.ravel())[0, 1])

    lower = [-_MAX_OUTSET, 1 - _MAX_INSET, -_MAX_OUTSET, 1 - _MAX_INSET]
    upper = [_MAX_INSET, 1 + _MAX_OUTSET, _MAX_INSET, 1 + _MAX_OUTSET]
    simplex = np.vstack([full, full + np.diag([_SIMPLEX_STEP, -_SIMPLEX_STEP, _SIMPLEX_STEP, -_SIMPLEX_STEP])])
    res = optimize.minimize(cost, full, method="Nelder-Mead", bounds=list(zip(lower, upper)),
                            options={"initial_simplex": simplex, "xatol": 1e-3, "fatol": 1e-5, "maxfev": 400})
    rect = res.x if res.fun < cost(full) else full
    return rect, resampled(rect)


def compare(pixels: np.ndarray, thumb: np.ndarray, aspect_tolerance: float, blur_px: float,
            change_threshold: float) -> Comparison:
    """Compare the thumbnail with the stored image.

    The thumbnail's picture area (:func:`content_box`) is matched to the part
    of the image it shows (:func:`_align`); both are blurred by a Gaussian of
    ``blur_px`` thumbnail pixels, because cameras decimate their thumbnails
    with little filtering and sharpen them differently, so fine texture must
    not count. The thumbnail's luma is then fitted as a non-decreasing
    function of the image's (:func:`monotone_fit`: cameras render thumbnails
    with their own tone curve), and the absolute residual is thresholded at
    ``change_threshold``.

    Parameters
    ----------
    pixels : ndarray, shape (H, W) or (H, W, C)
        The evidence's stored grid.
    thumb : ndarray, shape (h, w)
        Thumbnail luma in [0, 1].
    aspect_tolerance : float
        Allowed ``|ln(aspect ratio)|`` difference, before the rounding allowance.
    blur_px : float
        Gaussian standard deviation, thumbnail pixels (after binning to at
        most ``_WORK_PX`` on the longer side).
    change_threshold : float
        Residual luma (on [0, 1]) above which a thumbnail pixel counts as changed.
    """
    H, W = pixels.shape[:2]
    aspect_image = W / H
    # Phones store 512 x 384 thumbnails; binning them to at most _WORK_PX
    # keeps the alignment's cost that of a 160 x 120 one. Results are given
    # in the stored thumbnail's pixels.
    f = max(1, math.ceil(max(thumb.shape) / _WORK_PX))
    if f > 1:
        th, tw = thumb.shape[0] // f, thumb.shape[1] // f
        thumb = thumb[:th * f, :tw * f].reshape(th, f, tw, f).mean(axis=(1, 3))
    x0, y0, x1, y1 = content_box(thumb, aspect_image)
    box = (x0 * f, y0 * f, x1 * f, y1 * f)
    w, h = x1 - x0, y1 - y0
    tol = aspect_tolerance + 1.5 / min(w, h)
    diff = abs(math.log((w / h) / aspect_image))
    rotated = abs(math.log((w / h) * aspect_image)) <= tol < diff
    result = Comparison(box, aspect_image, w / h, diff, tol, rotated)
    if min(w, h) < 8:
        return result
    t = ndimage.gaussian_filter(thumb[y0:y1, x0:x1], blur_px, mode="nearest")
    # The image at _OVERSAMPLE times the picture area's size, low-passed for
    # sampling at the thumbnail's pitch.
    image = ndimage.gaussian_filter(luma_of(reduced_image(pixels, (_OVERSAMPLE * w, _OVERSAMPLE * h))),
                                    _OVERSAMPLE / 2)
    if t.std() < 1e-6 or image.std() < 1e-6:
        return result
    rect, m = _align(t, image, blur_px)
    if m.std() < 1e-6:
        return result
    residual = np.abs(t - monotone_fit(m.ravel(), t.ravel()).reshape(t.shape))
    # The picture area's outermost lines carry the camera's resampling and
    # block-padding artefacts (a 2-pixel column on an HP PhotoSmart C812):
    # they count in the residual but cannot form a changed region.
    interior = np.zeros_like(residual, dtype=bool)
    interior[_EDGE_PX:-_EDGE_PX, _EDGE_PX:-_EDGE_PX] = True
    labels, n = ndimage.label((residual > change_threshold) & interior)
    region_fraction, changed_box = 0.0, None
    outside = np.ones_like(residual, dtype=bool)
    if n:
        sizes = np.bincount(labels.ravel())[1:]
        largest = int(np.argmax(sizes))
        sl = ndimage.find_objects(labels)[largest]
        region_fraction = float(sizes[largest]) / residual.size
        changed_box = tuple(f * v for v in (sl[1].start + x0, sl[0].start + y0, sl[1].stop + x0, sl[0].stop + y0))
        # The blur spreads the region by about two standard deviations.
        outside = ~ndimage.binary_dilation(labels == largest + 1, iterations=max(1, round(2 * blur_px)))
    correlation = float(np.corrcoef(t.ravel(), m.ravel())[0, 1])
    rest = t[outside], m[outside]
    correlation_outside = (float(np.corrcoef(*rest)[0, 1])
                           if rest[0].size >= 16 and rest[0].std() > 1e-6 and rest[1].std() > 1e-6 else None)
    mse = float(np.mean(residual**2))
    return Comparison(
        box, aspect_image, w / h, diff, tol, rotated,
        image_rect=(float(rect[0]), float(rect[2]), float(rect[1]), float(rect[3])),
        correlation=correlation,
        correlation_outside=correlation_outside,
        psnr_db=10.0 * math.log10(1.0 / mse) if mse > 1e-12 else 99.0,
        changed_fraction=float((residual > change_threshold).mean()),
        region_fraction=region_fraction,
        changed_box=changed_box,
        difference=np.repeat(np.repeat(residual, f, axis=0), f, axis=1),
    )


@dataclass(frozen=True)
class ThumbnailThresholds:
    """The thresholds of the thumbnail check (see :data:`..detector.DEFAULT_PARAMS`)."""

    max_bytes: int
    max_pixels: int
    aspect_tolerance: float
    min_correlation: float
    blur_px: float
    change_threshold: float
    max_region_fraction: float


def accepted(thumb: EmbeddedThumbnail | None, limits: ThumbnailThresholds) -> Image.Image | None:
    """The intake's decoded thumbnail as RGB, or None when there is none or ``limits`` refuse it."""
    if thumb is None or thumb.refusal(limits.max_bytes, limits.max_pixels) is not None:
        return None
    return thumb.image()


def _details(img: Image.Image | None, cmp: Comparison | None, limits: ThumbnailThresholds, **extra) -> dict:
    out = {
        "present": img is not None,
        "width": img.size[0] if img is not None else None,
        "height": img.size[1] if img is not None else None,
        "thresholds": {
            "max_bytes": limits.max_bytes, "max_pixels": limits.max_pixels,
            "aspect_tolerance": limits.aspect_tolerance, "min_correlation": limits.min_correlation,
            "blur_px": limits.blur_px, "change_threshold": limits.change_threshold,
            "max_region_fraction": limits.max_region_fraction,
        },
        **extra,
    }
    if cmp is not None:
        out.update({
            "box": list(cmp.box),
            "aspect_image": round(cmp.aspect_image, 4),
            "aspect_thumbnail": round(cmp.aspect_thumbnail, 4),
            "aspect_difference": round(cmp.aspect_difference, 4),
            "aspect_tolerance_applied": round(cmp.aspect_tolerance, 4),
            "rotated": cmp.rotated,
            "correlation": None if cmp.correlation is None else round(cmp.correlation, 4),
            "correlation_outside": None if cmp.correlation_outside is None else round(cmp.correlation_outside, 4),
            "image_rect": None if cmp.image_rect is None else [round(v, 4) for v in cmp.image_rect],
            "psnr_db": None if cmp.psnr_db is None else round(cmp.psnr_db, 2),
            "changed_fraction": None if cmp.changed_fraction is None else round(cmp.changed_fraction, 4),
            "region_fraction": None if cmp.region_fraction is None else round(cmp.region_fraction, 4),
            "changed_box": None if cmp.changed_box is None else list(cmp.changed_box),
        })
    return out


def thumbnail_check(thumb: EmbeddedThumbnail | None, pixels: np.ndarray,
                    limits: ThumbnailThresholds) -> tuple[Check, dict]:
    """The thumbnail check and its numbers for the finding's details.

    Parameters
    ----------
    thumb : EmbeddedThumbnail or None
        The thumbnail as the intake read it (``Evidence.thumbnail``).
    pixels : ndarray, shape (H, W) or (H, W, C)
        The evidence's stored grid.
    limits : ThumbnailThresholds
        The check's thresholds; its byte and pixel limits refuse a thumbnail
        the intake accepted as the intake refuses one, with the same sentence.

    Returns
    -------
    check : Check
    details : dict
        For the finding's ``details["thumbnail"]``.
    """
    title = "Embedded thumbnail"
    reason = None if thumb is None else thumb.refusal(limits.max_bytes, limits.max_pixels)
    if reason is not None:
        return (Check("thumbnail", title, "note", f"The EXIF names a thumbnail that cannot be used: {reason}."),
                _details(None, None, limits, error=reason))
    img = None if thumb is None else thumb.image()
    if img is None:
        return (Check("thumbnail", title, "not available", "The file carries no JPEG thumbnail in IFD1."),
                _details(None, None, limits))
    thumb = luma_of(img)
    cmp = compare(pixels, thumb, limits.aspect_tolerance, limits.blur_px, limits.change_threshold)
    size = f"{img.size[0]} x {img.size[1]}"
    turned = 0
    portrait_image, portrait_thumb = pixels.shape[0] > pixels.shape[1], img.size[1] > img.size[0]
    if _verdict(cmp, limits) != "match" and portrait_image != portrait_thumb:
        # Viewers and operating systems turn photos losslessly without
        # updating the thumbnail: compare with the image turned back.
        # The turn that explains the thumbnail best: a match, then a local
        # difference, then the highest correlation.
        rank = {"match": 2, "local": 1}
        candidates = [(cmp, 0)] + [(compare(np.rot90(pixels, k), thumb, limits.aspect_tolerance, limits.blur_px,
                                            limits.change_threshold), k) for k in (1, 3)]
        cmp, turned = max(candidates, key=lambda c: (rank.get(_verdict(c[0], limits), 0), c[0].correlation or -1.0))
    details = _details(img, cmp, limits, turned_degrees=90 * turned)
    if cmp.correlation is None:
        return Check("thumbnail", title, "note",
                     f"The {size} thumbnail or the image is flat or too small to compare."), details
    verdict = _verdict(cmp, limits)
    numbers = (f"correlation {cmp.correlation:.3f} (minimum {limits.min_correlation:g}), PSNR {cmp.psnr_db:.1f} dB, "
               f"largest region differing by more than {limits.change_threshold:g} in luma "
               f"{100 * cmp.region_fraction:.2f}% of its area (maximum {100 * limits.max_region_fraction:g}%)")
    turn = f" once the image is turned back by {90 * turned} degrees" if turned else ""
    if verdict == "local":
        x0, y0, x1, y1 = cmp.changed_box
        return Check("thumbnail", title, "suspicious",
                     f"The {size} thumbnail differs from the stored picture{turn} in places: {numbers}; largest "
                     f"differing region at thumbnail pixels ({x0}, {y0})-({x1}, {y1}), the rest matching (correlation "
                     f"{cmp.correlation_outside:.3f})."), details
    squeezed = cmp.aspect_difference > cmp.aspect_tolerance
    if verdict == "different":
        framing = ""
        if squeezed:
            how = ("the image turned by 90 degrees" if cmp.rotated
                   else "another framing: the image was cropped or the thumbnail belongs to another picture")
            framing = (f"; its picture has aspect ratio {cmp.aspect_thumbnail:.3f}, the image {cmp.aspect_image:.3f} "
                       f"(log difference {cmp.aspect_difference:.3f} > {cmp.aspect_tolerance:.3f}), so it shows {how}")
        return Check("thumbnail", title, "suspicious",
                     f"The {size} thumbnail does not show the stored picture{turn}: {numbers}{framing}."), details
    x0, y0, x1, y1 = cmp.image_rect
    shown = (f"; it shows {100 * (x1 - x0):.0f}% x {100 * (y1 - y0):.0f}% of the image, as cameras that crop their "
             "thumbnail do" if min(x1 - x0, y1 - y0) < 0.97 else "")
    if squeezed:
        shown += (f"; its picture ({cmp.aspect_thumbnail:.3f}) is the image ({cmp.aspect_image:.3f}) squeezed into the "
                  "thumbnail's fixed frame")
    if turned:
        return (Check("thumbnail", title, "note",
                      f"The {size} thumbnail matches the stored picture{turn}: {numbers}{shown}. The pixels were "
                      "turned after the thumbnail was written, as viewers and operating systems do without changing "
                      "the picture; the file is not as the camera wrote it."), details)
    return (Check("thumbnail", title, "consistent",
                  f"The {size} thumbnail matches the stored picture: {numbers}{shown}."), details)


def _verdict(cmp: Comparison, limits: ThumbnailThresholds) -> str:
    """``"match"``, ``"local"`` (one region differs, the rest matches), ``"different"`` or ``"none"`` (not compared)."""
    if cmp.correlation is None:
        return "none"
    if (cmp.region_fraction > limits.max_region_fraction and cmp.correlation_outside is not None
            and cmp.correlation_outside >= limits.min_correlation):
        return "local"
    if cmp.correlation < limits.min_correlation or cmp.region_fraction > limits.max_region_fraction:
        return "different"
    return "match"
