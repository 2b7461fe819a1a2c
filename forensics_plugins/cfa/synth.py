"""Raw-like synthetic photos, authentic and spliced with another CFA phase, for validation.

A scene is a "dead leaves" picture (Lee, Mumford & Huang, 2001; the texture
target of camera evaluation, Cao, Guichard & Hornung, 2009): occluding disks
and ellipses with a power-law size distribution, each filled with a natural
texture (photographs and greyscale surfaces bundled with scikit-image, tinted),
under a smooth illumination. It is painted at twice the output size and
reduced by 2 x 2 averaging, which cancels exactly any period-2 structure,
so the demosaicing traces of the source photographs are erased; an optical
blur follows.

The camera then samples the scene through a Bayer pattern with
signal-dependent sensor noise (variance ``a * x + b`` in linear units),
quantised to 12 bits, demosaics it with one of the algorithms of
:mod:`.demosaic`, applies white balance, a colour matrix and the sRGB tone
curve, and quantises to 8 bits.

A spliced photo replaces a blob or rectangle covering 10-30 % of the frame by
the same area of another scene, taken with the pattern shifted by one pixel
horizontally, vertically or both (so its pattern differs from the host's),
possibly demosaiced by the other algorithm. The host of a spliced case is
the authentic case of the same seed, so the two differ only in the mask.
"""

from __future__ import annotations

import io
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Any

import numpy as np
from PIL import Image
from scipy import ndimage

from forensics_core import SyntheticCase

from .bayer import PATTERNS, mosaic, shifted
from .demosaic import ALGORITHMS, demosaic

SHIFTS = ((0, 1), (1, 0), (1, 1))
"""Pattern shifts ``(dy, dx)`` of a pasted region: green moves diagonal, or red and blue swap."""

_COLOUR_SOURCES = ("astronaut", "chelsea", "coffee", "rocket", "immunohistochemistry")
_GREY_SOURCES = ("brick", "grass", "gravel")
# A typical camera-to-sRGB matrix (rows sum to 1, so grey stays grey).
_COLOUR_MATRIX = np.array([[1.62, -0.47, -0.15], [-0.24, 1.52, -0.28], [-0.04, -0.52, 1.56]])
_RAW_LEVELS = 4095.0


@dataclass(frozen=True)
class CameraParams:
    """How a synthetic camera turns a scene into a stored photo.

    Attributes
    ----------
    pattern : str
        Bayer pattern of the sensor in the stored grid.
    algorithm : str
        Demosaicing algorithm (:data:`.demosaic.ALGORITHMS`).
    noise_a, noise_b : float
        Sensor noise variance ``a * x + b`` for a raw value ``x`` in [0, 1].
    wb : tuple of float
        White-balance gains applied after demosaicing (the raw is divided by them).
    matrix_strength : float
        Blend between the identity (0) and the typical colour matrix (1).
    """

    pattern: str
    algorithm: str
    noise_a: float
    noise_b: float
    wb: tuple[float, float, float]
    matrix_strength: float


@dataclass
class SynthPhoto:
    """One rendered photo before encoding, with its truth.

    Attributes
    ----------
    rgb : ndarray of uint8, shape (H, W, 3)
    mask : ndarray of bool, shape (H, W) or None
        True on pasted pixels.
    params : dict
        Everything that regenerates the photo.
    """

    rgb: np.ndarray
    mask: np.ndarray | None
    params: dict[str, Any] = field(default_factory=dict)


@lru_cache(maxsize=1)
def _textures() -> tuple[np.ndarray, ...]:
    """The bundled photographs and surfaces as linear RGB float32 in [0, 1]."""
    import skimage.data

    out = []
    for name in _COLOUR_SOURCES:
        out.append(getattr(skimage.data, name)()[..., :3])
    for name in _GREY_SOURCES:
        grey = getattr(skimage.data, name)()
        out.append(np.repeat(grey[..., None], 3, axis=2))
    return tuple(((t.astype(np.float32) / 255.0) ** 2.2) for t in out)


def _mirrored(n: int, start: int, size: int) -> np.ndarray:
    """Indices ``start .. start + n`` folded into ``[0, size)`` by mirroring."""
    i = (np.arange(start, start + n) % (2 * size))
    return np.where(i < size, i, 2 * size - 1 - i)


def _texture_patch(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """A tinted, mirrored-tiled patch of a random texture, shape ``shape + (3,)``."""
    textures = _textures()
    tex = textures[rng.integers(len(textures))]
    if rng.random() < 0.5:
        tex = tex[:, ::-1]
    if rng.random() < 0.5:
        tex = tex.transpose(1, 0, 2)
    rows = _mirrored(shape[0], int(rng.integers(0, 4 * tex.shape[0])), tex.shape[0])
    cols = _mirrored(shape[1], int(rng.integers(0, 4 * tex.shape[1])), tex.shape[1])
    tint = rng.uniform(0.6, 1.0, 3).astype(np.float32)
    gain = np.float32(rng.uniform(0.25, 1.4) / tint.max())
    return tex[np.ix_(rows, cols)] * (tint * gain)


def dead_leaves(rng: np.random.Generator, size: tuple[int, int], leaves: int = 160) -> np.ndarray:
    """A textured dead-leaves scene at twice ``size``.

    Parameters
    ----------
    rng : numpy Generator
    size : (H, W)
        Output size in pixels; the canvas is ``(2H, 2W)``.
    leaves : int
        Number of disks and ellipses painted back to front.

    Returns
    -------
    ndarray of float32, shape (2H, 2W, 3)
        Linear radiance, roughly in [0, 1.4].
    """
    h, w = 2 * size[0], 2 * size[1]
    canvas = _texture_patch(rng, (h, w))
    r_min, r_max = 0.03 * min(h, w), 0.45 * min(h, w)
    # Radii with density proportional to r^-3 (scale invariance), by inversion of the CDF.
    u = rng.random(leaves)
    radii = (r_min ** -2 - u * (r_min ** -2 - r_max ** -2)) ** -0.5
    for r in radii:
        cy, cx = rng.uniform(-0.1 * h, 1.1 * h), rng.uniform(-0.1 * w, 1.1 * w)
        aspect = rng.uniform(0.4, 1.0) if rng.random() < 0.5 else 1.0
        angle = rng.uniform(0, np.pi)
        y0, y1 = max(0, int(cy - r)), min(h, int(cy + r) + 1)
        x0, x1 = max(0, int(cx - r)), min(w, int(cx + r) + 1)
        if y0 >= y1 or x0 >= x1:
            continue
        yy = np.arange(y0, y1, dtype=np.float32)[:, None] - cy
        xx = np.arange(x0, x1, dtype=np.float32)[None, :] - cx
        ca, sa = np.cos(angle), np.sin(angle)
        u_ = (xx * ca + yy * sa) / r
        v_ = (-xx * sa + yy * ca) / (r * aspect)
        inside = u_ * u_ + v_ * v_ <= 1.0
        if not inside.any():
            continue
        patch = _texture_patch(rng, (y1 - y0, x1 - x0))
        view = canvas[y0:y1, x0:x1]
        view[inside] = patch[inside]
    return canvas


def _illumination(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """A smooth light falloff: a random linear gradient times lens vignetting, shape (H, W, 1)."""
    h, w = shape
    y = np.linspace(-1, 1, h, dtype=np.float32)[:, None]
    x = np.linspace(-1, 1, w, dtype=np.float32)[None, :]
    theta = rng.uniform(0, 2 * np.pi)
    ramp = 1.0 + rng.uniform(0.0, 0.4) * (np.cos(theta) * x + np.sin(theta) * y)
    vignette = 1.0 - rng.uniform(0.1, 0.35) * (x * x + y * y) / 2
    return (ramp * vignette / ramp.max())[..., None]


def render_scene(seed: int, size: tuple[int, int]) -> np.ndarray:
    """The linear radiance a camera sees for ``seed``, shape (H, W, 3), float32 in about [0, 1.2].

    Painted at twice the size, reduced by 2 x 2 means (which zero any
    period-2 pattern of the source textures), lit, then blurred by a
    Gaussian optical point-spread of standard deviation 0.35-0.6 px.
    """
    rng = np.random.default_rng([seed, 0xCFA])
    canvas = dead_leaves(rng, size)
    h, w = size
    scene = canvas.reshape(h, 2, w, 2, 3).mean(axis=(1, 3))
    scene *= _illumination(rng, size)
    sigma = rng.uniform(0.35, 0.6)
    scene = ndimage.gaussian_filter(scene, (sigma, sigma, 0), mode="mirror")
    # Ambient light keeps the deepest shadows just above black, as in a photo.
    return np.float32(0.01) + scene / np.float32(np.percentile(scene, 99.5) / 0.9)


def random_camera(rng: np.random.Generator, pattern: str | None = None, algorithm: str | None = None) -> CameraParams:
    """Draw a camera: pattern, algorithm, noise (ISO 100-1600 like), white balance and colour matrix."""
    return CameraParams(
        pattern=pattern or PATTERNS[rng.integers(4)],
        algorithm=algorithm or ALGORITHMS[rng.integers(len(ALGORITHMS))],
        noise_a=float(10 ** rng.uniform(-4.0, -2.8)),
        noise_b=float(10 ** rng.uniform(-6.0, -5.0)),
        wb=(float(rng.uniform(1.6, 2.4)), 1.0, float(rng.uniform(1.3, 2.0))),
        matrix_strength=float(rng.uniform(0.25, 0.7)),
    )


def _srgb(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) on values in [0, 1]."""
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * np.power(linear, 1 / 2.4) - 0.055)


def capture(scene: np.ndarray, camera: CameraParams, rng: np.random.Generator) -> np.ndarray:
    """Photograph a linear scene: mosaic, noise, 12-bit raw, demosaic, colour, tone curve.

    Parameters
    ----------
    scene : ndarray, shape (H, W, 3)
        Linear radiance, about [0, 1].
    camera : CameraParams
    rng : numpy Generator
        Noise stream.

    Returns
    -------
    ndarray of float64, shape (H, W, 3)
        Display-referred sRGB in [0, 1], before 8-bit quantisation.
    """
    wb = np.asarray(camera.wb)
    raw = mosaic(scene.astype(np.float64) / wb, camera.pattern)
    raw = raw + np.sqrt(camera.noise_a * np.clip(raw, 0, None) + camera.noise_b) * rng.standard_normal(raw.shape)
    raw = np.round(np.clip(raw, 0.0, 1.0) * _RAW_LEVELS) / _RAW_LEVELS
    rgb = demosaic(raw, camera.pattern, camera.algorithm) * wb
    t = camera.matrix_strength
    matrix = (1 - t) * np.eye(3) + t * _COLOUR_MATRIX
    rgb = np.clip(rgb @ matrix.T, 0.0, 1.0)
    return _srgb(rgb)


def _to_uint8(rgb: np.ndarray) -> np.ndarray:
    return np.round(np.clip(rgb, 0.0, 1.0) * 255.0).astype(np.uint8)


def blob_mask(rng: np.random.Generator, shape: tuple[int, int], fraction: float, rectangle: bool) -> np.ndarray:
    """A random region covering ``fraction`` of the frame, inside it.

    A rectangle of random aspect, or a star-shaped blob whose radius varies
    smoothly with the angle (harmonics 2 to 4).

    Returns
    -------
    ndarray of bool, shape (H, W)
    """
    h, w = shape
    target = fraction * h * w
    if rectangle:
        aspect = rng.uniform(0.5, 2.0)
        bh = int(round(min(h - 2, np.sqrt(target / aspect))))
        bw = int(round(min(w - 2, target / max(bh, 1))))
        y0, x0 = rng.integers(0, h - bh + 1), rng.integers(0, w - bw + 1)
        mask = np.zeros(shape, dtype=bool)
        mask[y0:y0 + bh, x0:x0 + bw] = True
        return mask
    amps = rng.uniform(0.0, 0.18, 3)
    phases = rng.uniform(0, 2 * np.pi, 3)
    theta = np.linspace(0, 2 * np.pi, 721)
    rel = 1.0 + sum(a * np.cos(k * theta + p) for k, a, p in zip((2, 3, 4), amps, phases))
    r0 = np.sqrt(target / (0.5 * np.trapezoid(rel ** 2, theta)))
    reach = r0 * rel.max()
    reach_y, reach_x = min(reach, h / 2 - 1), min(reach, w / 2 - 1)
    cy, cx = rng.uniform(reach_y, h - reach_y), rng.uniform(reach_x, w - reach_x)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    ang = np.arctan2(yy - cy, xx - cx) % (2 * np.pi)
    radius = r0 * np.interp(ang, theta, rel)
    return (yy - cy) ** 2 + (xx - cx) ** 2 <= radius ** 2


def _host(seed: int, size: tuple[int, int], algorithm: str | None) -> tuple[CameraParams, np.ndarray, dict[str, Any]]:
    """The camera, the captured photo (float sRGB) and the parameters of the authentic photo of ``seed``."""
    camera = random_camera(np.random.default_rng([seed, 0xCA3E]), algorithm=algorithm)
    host = capture(render_scene(seed, size), camera, np.random.default_rng([seed, 1]))
    params: dict[str, Any] = {"seed": seed, "size": list(size), "pattern": camera.pattern,
                              "demosaic": camera.algorithm, "noise_a": camera.noise_a, "noise_b": camera.noise_b}
    return camera, host, params


def make_pair(
    seed: int,
    size: tuple[int, int] = (512, 512),
    *,
    algorithm: str | None = None,
    shift: tuple[int, int] | None = None,
    donor_algorithm: str | None = None,
    donor_camera: str = "same_model",
    fraction: float | None = None,
) -> tuple[SynthPhoto, SynthPhoto]:
    """Render the authentic photo of ``seed`` and its spliced version, which differ only inside the mask.

    Parameters
    ----------
    seed : int
    size : (H, W)
        Pixels.
    algorithm, shift, donor_algorithm, fraction
        Fix the host's demosaicing, the donor's pattern shift ``(dy, dx)``, its
        demosaicing (by default the host's) and the pasted area fraction;
        drawn from ``seed`` when None.
    donor_camera : {"same_model", "other"}
        ``same_model``: the donor photo was taken with the host's camera model
        (same colour processing, white balance within 10 %, another ISO);
        ``other``: every camera setting is drawn anew.

    Returns
    -------
    (SynthPhoto, SynthPhoto)
        Authentic, spliced.
    """
    if donor_camera not in ("same_model", "other"):
        raise ValueError(f"donor_camera must be 'same_model' or 'other', not {donor_camera!r}")
    camera, host, params = _host(seed, size, algorithm)
    srng = np.random.default_rng([seed, 0x5E11CE])
    shift = shift or SHIFTS[srng.integers(len(SHIFTS))]
    fraction = fraction if fraction is not None else float(srng.uniform(0.10, 0.30))
    other = random_camera(srng, pattern=shifted(camera.pattern, *shift),
                          algorithm=donor_algorithm or camera.algorithm)
    if donor_camera == "same_model":
        jitter = srng.uniform(0.9, 1.1, 3)
        other = replace(camera, pattern=other.pattern, algorithm=other.algorithm, noise_a=other.noise_a,
                        noise_b=other.noise_b, wb=tuple(float(g * j) for g, j in zip(camera.wb, jitter)))
    donor = capture(render_scene(seed + 7919, size), other, np.random.default_rng([seed, 2]))
    mask = blob_mask(srng, size, fraction, rectangle=bool(srng.random() < 0.3))
    spliced = np.where(mask[..., None], donor, host)
    splice_params = {**params, "shift": list(shift), "donor_pattern": other.pattern,
                     "donor_demosaic": other.algorithm, "donor_camera": donor_camera, "fraction": float(mask.mean())}
    return SynthPhoto(_to_uint8(host), None, params), SynthPhoto(_to_uint8(spliced), mask, splice_params)


def make_photo(seed: int, size: tuple[int, int] = (512, 512), *, spliced: bool = False, **kwargs: Any) -> SynthPhoto:
    """The authentic photo of ``seed``, or its spliced version (keywords as in :func:`make_pair`)."""
    if spliced:
        return make_pair(seed, size, **kwargs)[1]
    _, host, params = _host(seed, size, kwargs.get("algorithm"))
    return SynthPhoto(_to_uint8(host), None, params)


def encode(rgb: np.ndarray, jpeg_quality: int | None = None, resize: float | None = None) -> tuple[bytes, str]:
    """Store a photo as PNG, or as JPEG (4:2:0, Pillow's default) of the given quality, optionally resized.

    Returns
    -------
    (bytes, suffix)
    """
    img = Image.fromarray(rgb)
    if resize is not None:
        img = img.resize((round(img.width * resize), round(img.height * resize)), Image.Resampling.BICUBIC)
    out = io.BytesIO()
    if jpeg_quality is None:
        img.save(out, format="PNG")
        return out.getvalue(), ".png"
    img.save(out, format="JPEG", quality=int(jpeg_quality))
    return out.getvalue(), ".jpg"


def resized_mask(mask: np.ndarray, resize: float | None) -> np.ndarray:
    """The paste mask on the grid of a photo resized by ``resize`` (as :func:`encode` does)."""
    if resize is None:
        return mask
    img = Image.fromarray(mask.astype(np.uint8) * 255)
    img = img.resize((round(img.width * resize), round(img.height * resize)), Image.Resampling.BILINEAR)
    return np.asarray(img) >= 128


# Storage conditions of the validation suite: mostly lossless or near-lossless,
# where the trace survives, plus strong JPEG and resizing, which erase it.
_STORAGE = ((None, None), (None, None), (None, None), (98, None), (95, None), (75, None), (None, 0.75))


def synthetic_cases(seed: int, count: int, size: tuple[int, int] = (864, 1152)) -> Iterator[SyntheticCase]:
    """``count`` authentic and ``count`` spliced cases for ``forensics validate``.

    Pair ``i`` (an authentic photo and its spliced version) uses the seed
    ``seed * 100003 + i``; its demosaicing alternates between the two
    algorithms, its storage cycles through PNG, JPEG 98 and 95 (the trace
    survives), JPEG 75 and a 0.75 resize (it fades or goes), and every fifth
    donor comes from another camera (all settings drawn anew) rather than
    from the host's camera model.
    """
    for i in range(count):
        case_seed = seed * 100003 + i
        algorithm = ALGORITHMS[i % len(ALGORITHMS)]
        quality, resize = _STORAGE[i % len(_STORAGE)]
        donor = "other" if i % 5 == 4 else "same_model"
        for photo in make_pair(case_seed, size, algorithm=algorithm, donor_camera=donor):
            spliced = photo.mask is not None
            data, suffix = encode(photo.rgb, quality, resize)
            mask = resized_mask(photo.mask, resize) if spliced else None
            shift = photo.params.get("shift")
            h, w = Image.open(io.BytesIO(data)).size[::-1]
            yield SyntheticCase(
                name=f"cfa-{'spliced' if spliced else 'authentic'}-{case_seed}",
                data=data,
                suffix=suffix,
                spliced=spliced,
                mask=mask,
                conditions={
                    "kind": "other_cfa_phase" if spliced else "none",
                    "shift": f"{shift[0]},{shift[1]}" if spliced else "none",
                    "demosaic": algorithm,
                    "donor": donor if spliced else "none",
                    "donor_demosaic": photo.params.get("donor_demosaic", "none"),
                    "jpeg_quality": str(quality) if quality is not None else "none",
                    "resize": str(resize) if resize is not None else "none",
                    "size": f"{w}x{h}",
                },
            )
