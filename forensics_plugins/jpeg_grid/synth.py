"""Synthetic JPEG photos with known block grids, authentic and spliced, for validation.

A scene is a photograph bundled with scikit-image (read offline), cropped at
random and resized to the requested size, given fine detail that the small
originals lack (a multiplicative 1/f texture), then passed through a simple
camera: a Bayer RGGB mosaic with bilinear demosaicing and sensor noise. Other
detectors therefore see an ordinary camera photo, with a CFA trace and no
JPEG history until the first compression.

Kinds (``conditions["kind"]``):

``none``
    authentic: the scene compressed once at quality ``q`` on the grid (0, 0);
``recompressed``
    authentic: the same, decoded and saved again at quality ``q2`` on the same
    grid (a photo re-saved without edit);
``never_compressed``
    authentic: the scene saved as PNG, never JPEG-compressed (the detector must
    answer inconclusive, not clean);
``copy_move``
    a region of the decoded JPEG is copied to a place displaced by an offset
    that is not a multiple of 8, so its block grid is shifted there, and the
    whole is saved again at quality ``q2``;
``splice``
    a region of another scene, compressed at quality ``qp`` on a grid shifted
    by ``(dx, dy) != (0, 0)`` modulo 8, is pasted and the whole is saved again
    at quality ``q2``;
``uncompressed_paste``
    a region of another scene never JPEG-compressed is pasted into the decoded
    JPEG and the whole is saved losslessly (PNG): the main grid is missing
    there.

The paste region is an ellipse or a rectangle covering 15-30 % of the frame.
Every case carries its paste mask and the parameters that regenerate it.
"""

from __future__ import annotations

import io
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from PIL import Image
from scipy import ndimage

from forensics_core import SyntheticCase

SOURCES = ("astronaut", "coffee", "chelsea", "rocket", "camera")
SPLICE_KINDS = ("copy_move", "splice")
# Spliced kinds of :func:`synthetic_cases`, in turn.
CASE_CYCLE = ("splice", "copy_move", "splice", "uncompressed_paste")
DEFAULT_SIZE = (864, 1152)
QUALITY_RANGE = (75, 95)
FINAL_QUALITY_RANGE = (90, 100)
AREA_RANGE = (0.15, 0.30)

# Bilinear demosaicing kernels: green from its four neighbours, red and blue
# from two or four.
_K_GREEN = np.array([[0, 1, 0], [1, 4, 1], [0, 1, 0]], dtype=np.float64) / 4.0
_K_RED_BLUE = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]], dtype=np.float64) / 4.0


def _source(name: str) -> Image.Image:
    """One of the bundled photographs as an RGB image."""
    from skimage import data

    return Image.fromarray(np.asarray(getattr(data, name)(), dtype=np.uint8)).convert("RGB")


def _fractal_texture(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """Zero-mean, unit-variance 1/f noise, shape ``shape``: detail at every scale like natural surfaces."""
    fy = np.fft.fftfreq(shape[0])[:, None]
    fx = np.fft.rfftfreq(shape[1])[None, :]
    radius = np.hypot(fx, fy)
    radius[0, 0] = 1.0
    spectrum = np.fft.rfft2(rng.standard_normal(shape)) / radius
    spectrum[0, 0] = 0.0
    tex = np.fft.irfft2(spectrum, s=shape)
    return tex / tex.std()


def _camera(rgb: np.ndarray, rng: np.random.Generator, noise: float) -> np.ndarray:
    """Bayer RGGB sampling, bilinear demosaicing and Gaussian sensor noise; ``rgb`` in [0, 255]."""
    h, w = rgb.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w]
    masks = ((yy % 2 == 0) & (xx % 2 == 0), (yy % 2) != (xx % 2), (yy % 2 == 1) & (xx % 2 == 1))
    out = np.empty_like(rgb)
    for c, (mask, kernel) in enumerate(zip(masks, (_K_RED_BLUE, _K_GREEN, _K_RED_BLUE))):
        sensed = np.where(mask, rgb[..., c] + rng.normal(0.0, noise, (h, w)), 0.0)
        out[..., c] = ndimage.convolve(sensed, kernel, mode="mirror")
    return out


def render_scene(rng: np.random.Generator, size: tuple[int, int], source: str) -> np.ndarray:
    """A camera-like photo of a random crop of ``source``.

    Parameters
    ----------
    rng : numpy.random.Generator
    size : (int, int)
        Output height and width, pixels.
    source : str
        Name of a :data:`SOURCES` photograph.

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
    """
    src = _source(source)
    sw, sh = src.size
    aspect = size[1] / size[0]
    crop_h = int(min(sh, sw / aspect) * rng.uniform(0.7, 1.0))
    crop_w = int(round(crop_h * aspect))
    y0 = int(rng.integers(0, sh - crop_h + 1))
    x0 = int(rng.integers(0, sw - crop_w + 1))
    resized = src.resize((size[1], size[0]), Image.Resampling.BICUBIC, box=(x0, y0, x0 + crop_w, y0 + crop_h))
    img = np.asarray(resized, dtype=np.float64) / 255.0
    texture = _fractal_texture(rng, size)
    img = np.clip(img * (1.0 + rng.uniform(0.04, 0.08) * texture[..., None]), 0.0, 1.0) * 255.0
    img = _camera(img, rng, noise=float(rng.uniform(1.0, 3.0)))
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


def jpeg_bytes(rgb: np.ndarray, quality: int, origin: tuple[int, int] = (0, 0)) -> bytes:
    """Encode ``rgb`` as a baseline JPEG whose 8x8 grid starts at ``origin`` = (dx, dy) of the image.

    The image is padded on the left and top by ``(8 - d) % 8`` pixels before
    encoding, so block boundaries fall at ``x = dx mod 8`` and ``y = dy mod 8``
    of the original frame; :func:`decode_cropped` removes the padding.
    """
    dx, dy = origin
    px, py = (8 - dx) % 8, (8 - dy) % 8
    pad = ((py, 0), (px, 0)) + (((0, 0),) if rgb.ndim == 3 else ())
    buf = io.BytesIO()
    Image.fromarray(np.pad(rgb, pad, mode="reflect")).save(buf, format="JPEG", quality=int(quality))
    return buf.getvalue()


def decode_cropped(data: bytes, origin: tuple[int, int] = (0, 0)) -> np.ndarray:
    """Decode what :func:`jpeg_bytes` encoded and remove its padding."""
    dx, dy = origin
    px, py = (8 - dx) % 8, (8 - dy) % 8
    with Image.open(io.BytesIO(data)) as img:
        arr = np.asarray(img.convert("RGB" if img.mode != "L" else "L"))
    return arr[py:, px:]


def paste_mask(rng: np.random.Generator, size: tuple[int, int], area: float) -> np.ndarray:
    """Boolean mask, shape ``size``, of an ellipse or rectangle of about ``area`` of the frame, anywhere inside it."""
    h, w = size
    aspect = rng.uniform(0.6, 1.6)
    ellipse = bool(rng.integers(0, 2))
    cover = area * h * w / (np.pi / 4.0 if ellipse else 1.0)
    bh = min(h - 2, int(round(np.sqrt(cover / aspect))))
    bw = min(w - 2, int(round(cover / bh)))
    y0 = int(rng.integers(1, h - bh))
    x0 = int(rng.integers(1, w - bw))
    yy, xx = np.mgrid[0:h, 0:w]
    if ellipse:
        cy, cx = y0 + bh / 2.0, x0 + bw / 2.0
        return ((yy + 0.5 - cy) / (bh / 2.0)) ** 2 + ((xx + 0.5 - cx) / (bw / 2.0)) ** 2 <= 1.0
    return (yy >= y0) & (yy < y0 + bh) & (xx >= x0) & (xx < x0 + bw)


@dataclass(frozen=True)
class Spliced:
    """A spliced JPEG with its truth.

    Attributes
    ----------
    data : bytes
        The final file (JPEG, or PNG for ``uncompressed_paste``).
    mask : ndarray, shape (H, W), bool
        True on pasted pixels.
    shift : (int, int) or None
        Grid origin (dx, dy) of the pasted pixels' first compression, pixels
        modulo 8; None when they were never compressed.
    params : dict
        Everything that regenerates the case.
    suffix : str
        File suffix of ``data``.
    """

    data: bytes
    mask: np.ndarray
    shift: tuple[int, int] | None
    params: dict
    suffix: str = ".jpg"


def _given(value, drawn):
    """``value`` if the caller gave one, else ``drawn``.

    The draw is made either way, so the rest of the random stream, hence the
    scene, does not depend on which parameters were given: a case's recorded
    parameters regenerate it.
    """
    return drawn if value is None else value


def _random_shift(rng: np.random.Generator) -> tuple[int, int]:
    code = int(rng.integers(1, 64))
    return code % 8, code // 8


def make_spliced(seed: int, kind: str, size: tuple[int, int] = DEFAULT_SIZE, quality: int | None = None,
                 paste_quality: int | None = None, final_quality: int | None = None,
                 source: str | None = None, shift: tuple[int, int] | None = None) -> Spliced:
    """A host JPEG with a region whose block grid is shifted, saved again.

    Parameters
    ----------
    seed : int
        Everything not given is drawn from it.
    kind : {"copy_move", "splice"}
    size : (int, int)
        Height and width, pixels.
    quality, paste_quality, final_quality : int, optional
        JPEG qualities of the host (first compression), of the pasted part's
        source (``splice`` only; ``copy_move`` copies the host) and of the final
        save. Defaults: drawn in :data:`QUALITY_RANGE` and
        :data:`FINAL_QUALITY_RANGE`.
    source : str, optional
        Host photograph; default drawn from :data:`SOURCES`.
    shift : (int, int), optional
        Grid origin (dx, dy) of the pasted pixels, not (0, 0) modulo 8;
        default drawn at random.
    """
    if kind not in SPLICE_KINDS:
        raise ValueError(f"unknown splice kind {kind!r}")
    rng = np.random.default_rng([seed, 1 + SPLICE_KINDS.index(kind)])
    source = _given(source, SOURCES[int(rng.integers(0, len(SOURCES)))])
    quality = _given(quality, int(rng.integers(QUALITY_RANGE[0], QUALITY_RANGE[1] + 1)))
    final_quality = _given(final_quality, int(rng.integers(FINAL_QUALITY_RANGE[0], FINAL_QUALITY_RANGE[1] + 1)))
    area = float(rng.uniform(*AREA_RANGE))
    mask = paste_mask(rng, size, area)
    host = decode_cropped(jpeg_bytes(render_scene(rng, size, source), quality))
    drawn = _random_shift(rng)
    shift = drawn if shift is None else (shift[0] % 8, shift[1] % 8)
    if shift == (0, 0):
        raise ValueError("the pasted grid must be shifted: shift (0, 0) modulo 8")
    if kind == "copy_move":
        paste_quality = quality
        # Content displaced by (ox, oy) carries the host grid shifted by the offset modulo 8.
        ys, xs = np.nonzero(mask)
        oy = _displacement(rng, int(ys.min()), int(ys.max()), size[0], shift[1])
        ox = _displacement(rng, int(xs.min()), int(xs.max()), size[1], shift[0])
        donor = np.roll(host, (oy, ox), axis=(0, 1))
        donor_source = source
    else:
        paste_quality = _given(paste_quality, int(rng.integers(QUALITY_RANGE[0], QUALITY_RANGE[1] + 1)))
        others = [s for s in SOURCES if s != source]
        donor_source = others[int(rng.integers(0, len(others)))]
        scene = render_scene(rng, size, donor_source)
        donor = decode_cropped(jpeg_bytes(scene, paste_quality, shift), shift)
    composite = np.where(mask[..., None] if host.ndim == 3 else mask, donor, host)
    data = jpeg_bytes(composite, final_quality)
    params = {"seed": seed, "kind": kind, "size": list(size), "source": source, "donor_source": donor_source,
              "quality": quality, "paste_quality": paste_quality, "final_quality": final_quality,
              "shift": list(shift), "area": round(float(mask.mean()), 4)}
    return Spliced(data=data, mask=mask, shift=shift, params=params)


def make_uncompressed_paste(seed: int, size: tuple[int, int] = DEFAULT_SIZE, quality: int | None = None,
                            source: str | None = None) -> Spliced:
    """A host JPEG, decoded, with a region of a never-compressed scene pasted, saved as PNG.

    Parameters are as for :func:`make_spliced`; the composite is never
    compressed again, so the host keeps its grid and the region has none.
    """
    rng = np.random.default_rng([seed, 7])
    source = _given(source, SOURCES[int(rng.integers(0, len(SOURCES)))])
    quality = _given(quality, int(rng.integers(QUALITY_RANGE[0], QUALITY_RANGE[1] + 1)))
    mask = paste_mask(rng, size, float(rng.uniform(*AREA_RANGE)))
    host = decode_cropped(jpeg_bytes(render_scene(rng, size, source), quality))
    others = [s for s in SOURCES if s != source]
    donor_source = others[int(rng.integers(0, len(others)))]
    composite = np.where(mask[..., None], render_scene(rng, size, donor_source), host)
    buf = io.BytesIO()
    Image.fromarray(composite).save(buf, format="PNG")
    params = {"seed": seed, "kind": "uncompressed_paste", "size": list(size), "source": source,
              "donor_source": donor_source, "quality": quality, "paste_quality": None, "final_quality": None,
              "shift": None, "area": round(float(mask.mean()), 4)}
    return Spliced(data=buf.getvalue(), mask=mask, shift=None, params=params, suffix=".png")


def _displacement(rng: np.random.Generator, first: int, last: int, extent: int, residue: int) -> int:
    """An offset ``o`` with ``o % 8 == residue`` such that ``first - o >= 0`` and ``last - o < extent``.

    The copied pixels are then read from inside the frame; when the region is
    too large for that, any offset with the residue is drawn (the copy wraps).
    """
    lo, hi = last - extent + 1, first
    choices = np.arange(lo, hi + 1)
    choices = choices[(choices % 8 == residue) & (np.abs(choices) >= 8)]
    if choices.size == 0:
        choices = np.arange(8, extent)
        choices = choices[choices % 8 == residue]
    return int(choices[int(rng.integers(0, choices.size))])


def make_authentic(seed: int, size: tuple[int, int] = DEFAULT_SIZE, quality: int | None = None,
                   source: str | None = None) -> tuple[bytes, dict]:
    """A scene compressed once on the grid (0, 0); returns the JPEG bytes and the parameters."""
    rng = np.random.default_rng([seed, 0])
    source = _given(source, SOURCES[int(rng.integers(0, len(SOURCES)))])
    quality = _given(quality, int(rng.integers(QUALITY_RANGE[0], QUALITY_RANGE[1] + 1)))
    data = jpeg_bytes(render_scene(rng, size, source), quality)
    return data, {"seed": seed, "kind": "none", "size": list(size), "source": source, "quality": quality}


def make_recompressed(seed: int, size: tuple[int, int] = DEFAULT_SIZE, quality: int | None = None,
                      final_quality: int | None = None, source: str | None = None) -> tuple[bytes, dict]:
    """A scene compressed at ``quality``, decoded and saved again at ``final_quality`` on the same grid.

    Authentic: a photo re-saved without any edit, the most common history
    after a camera's own compression.
    """
    rng = np.random.default_rng([seed, 50])
    source = _given(source, SOURCES[int(rng.integers(0, len(SOURCES)))])
    quality = _given(quality, int(rng.integers(QUALITY_RANGE[0], QUALITY_RANGE[1] + 1)))
    final_quality = _given(final_quality, int(rng.integers(FINAL_QUALITY_RANGE[0], FINAL_QUALITY_RANGE[1] + 1)))
    first = decode_cropped(jpeg_bytes(render_scene(rng, size, source), quality))
    return jpeg_bytes(first, final_quality), {"seed": seed, "kind": "recompressed", "size": list(size),
                                              "source": source, "quality": quality, "final_quality": final_quality}


def make_never_compressed(seed: int, size: tuple[int, int] = DEFAULT_SIZE,
                          source: str | None = None) -> tuple[bytes, dict]:
    """A scene saved as PNG, never JPEG-compressed; returns the PNG bytes and the parameters."""
    rng = np.random.default_rng([seed, 99])
    source = _given(source, SOURCES[int(rng.integers(0, len(SOURCES)))])
    buf = io.BytesIO()
    Image.fromarray(render_scene(rng, size, source)).save(buf, format="PNG")
    return buf.getvalue(), {"seed": seed, "kind": "never_compressed", "size": list(size), "source": source}


def _size_tag(size: tuple[int, int]) -> str:
    return f"{size[1]}x{size[0]}"


def synthetic_cases(seed: int, count: int, size: tuple[int, int] = DEFAULT_SIZE) -> Iterator[SyntheticCase]:
    """``count`` authentic and ``count`` spliced cases, deterministic from ``seed``.

    Authentic: one in eight (at least one) a never-compressed PNG, one in four
    a JPEG saved twice on the same grid, the rest single-compressed JPEGs.
    Spliced: in turn the kinds of :data:`CASE_CYCLE` (half splices, a quarter
    copy-moves, a quarter never-compressed pastes saved as PNG), final JPEG
    quality in :data:`FINAL_QUALITY_RANGE`.
    """
    n_png = max(1, count // 8) if count > 1 else 0
    n_recompressed = count // 4
    for i in range(count):
        case_seed = seed * 100_003 + i
        tags = {"size": _size_tag(size)}
        if i < n_png:
            data, params = make_never_compressed(case_seed, size)
            yield SyntheticCase(name=f"jpeg-grid-png-{seed}-{i}", data=data, suffix=".png", spliced=False,
                                conditions={"kind": "never_compressed", "jpeg_quality": "none",
                                            "source": params["source"], **tags})
        elif i < n_png + n_recompressed:
            data, params = make_recompressed(case_seed, size)
            yield SyntheticCase(name=f"jpeg-grid-recompressed-{seed}-{i}", data=data, suffix=".jpg", spliced=False,
                                conditions={"kind": "recompressed", "jpeg_quality": str(params["quality"]),
                                            "final_quality": str(params["final_quality"]),
                                            "source": params["source"], **tags})
        else:
            data, params = make_authentic(case_seed, size)
            yield SyntheticCase(name=f"jpeg-grid-authentic-{seed}-{i}", data=data, suffix=".jpg", spliced=False,
                                conditions={"kind": "none", "jpeg_quality": str(params["quality"]),
                                            "source": params["source"], **tags})
    for i in range(count):
        kind = CASE_CYCLE[i % len(CASE_CYCLE)]
        if kind == "uncompressed_paste":
            case = make_uncompressed_paste(seed * 100_003 + i, size)
        else:
            case = make_spliced(seed * 100_003 + i, kind, size)
        p = case.params
        shift = "none" if case.shift is None else f"{case.shift[0]},{case.shift[1]}"
        yield SyntheticCase(name=f"jpeg-grid-{kind.replace('_', '-')}-{seed}-{i}", data=case.data, suffix=case.suffix,
                            spliced=True, mask=case.mask,
                            conditions={"kind": kind, "jpeg_quality": str(p["quality"]),
                                        "paste_quality": str(p["paste_quality"] or "none"),
                                        "final_quality": str(p["final_quality"] or "lossless"),
                                        "shift": shift, "source": p["source"], "size": _size_tag(size)})
