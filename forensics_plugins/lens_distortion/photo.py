"""From a capture (:mod:`.render`) to the photo a user analyses, and the authentic photo.

Sensor noise, resizing and JPEG are the post-processing that authentic and
spliced outputs share. Scene, noise and splice draw on separate random
streams of the seed, so a splice (:mod:`.splice`) shares its host scene and
its noise with the authentic photo of the same seed.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from PIL import Image

from .render import render_scene
from .scene import random_scene
from .truth import SynthImage


@dataclass(frozen=True)
class PostProcessing:
    """What happens to a capture after the lens.

    Attributes
    ----------
    noise : float
        Standard deviation of Gaussian sensor noise, fraction of full scale.
    jpeg_quality : int or None
        Pillow JPEG quality; None keeps the lossless pixels.
    resize : float or None
        Final rescale factor (Lanczos) applied before JPEG.
    """

    noise: float
    jpeg_quality: int | None
    resize: float | None


def _add_noise(image: np.ndarray, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """Gaussian sensor noise (sigma in units of full scale), quantised to uint8."""
    noisy = image + sigma * rng.standard_normal(image.shape, dtype=np.float32)
    return np.round(np.clip(noisy, 0.0, 1.0) * 255.0).astype(np.uint8)


def _resized_shape(shape: tuple[int, int], factor: float | None) -> tuple[int, int]:
    if factor is None or factor == 1.0:
        return shape
    return max(int(round(shape[0] * factor)), 1), max(int(round(shape[1] * factor)), 1)


def resize_points(points: np.ndarray, shape_in: tuple[int, int], shape_out: tuple[int, int]) -> np.ndarray:
    """Pixel-centre coordinates under a resize that maps pixel edges onto pixel edges (Pillow's convention)."""
    factor = np.array([shape_out[1] / shape_in[1], shape_out[0] / shape_in[0]])
    return (np.asarray(points) + 0.5) * factor - 0.5


def finish(
    image: np.ndarray, alpha: np.ndarray | None, post: PostProcessing, rng: np.random.Generator
) -> tuple[np.ndarray, bytes | None, np.ndarray | None]:
    """Noise, resize and JPEG, identical for authentic and spliced images.

    Parameters
    ----------
    image : ndarray, shape (H, W, 3), float32
        Linear RGB in [0, 1], as captured.
    alpha : ndarray, shape (H, W), or None
        Paste opacity of a splice; None when authentic.
    post : PostProcessing
    rng : numpy.random.Generator
        The noise stream.

    Returns
    -------
    pixels : ndarray, shape (H', W', 3), uint8
        The final pixels (JPEG-decoded when ``data`` is set).
    data : bytes or None
        The JPEG file, None without JPEG.
    mask : ndarray, shape (H', W'), bool, or None
        Pixels with any pasted content; None when ``alpha`` is None.
    """
    pixels = _add_noise(image, post.noise, rng)
    out_shape = _resized_shape(pixels.shape[:2], post.resize)
    mask = None if alpha is None else alpha > 0
    if out_shape != pixels.shape[:2]:
        size = (out_shape[1], out_shape[0])
        pixels = np.asarray(Image.fromarray(pixels).resize(size, Image.Resampling.LANCZOS))
        if alpha is not None:
            resized = Image.fromarray(alpha.astype(np.float32), "F").resize(size, Image.Resampling.BILINEAR)
            mask = np.asarray(resized) > 1e-3
    if post.jpeg_quality is None:
        return pixels, None, mask
    buffer = io.BytesIO()
    Image.fromarray(pixels).save(buffer, format="JPEG", quality=int(post.jpeg_quality))
    data = buffer.getvalue()
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB")), data, mask


def seed_streams(seed: int) -> tuple[np.random.Generator, np.random.Generator, np.random.SeedSequence]:
    """Independent host-scene, noise and splice streams of one seed.

    Keeping them apart lets a splice share its host scene and its noise with
    the authentic image of the same seed.
    """
    host, noise, splice = np.random.SeedSequence(seed).spawn(3)
    return np.random.default_rng(host), np.random.default_rng(noise), splice


def image_params(kind: str, seed: int, *, size, k1, k2, centre, noise, blur, jpeg_quality, resize,
                 feather_px=None) -> dict:
    """The flat JSON-able arguments that regenerate an image (:attr:`.truth.SynthImage.params`).

    ``kind`` and ``seed`` name the image; the keywords are the arguments of
    :func:`render_authentic` (and ``feather_px`` of a splice's edge) that
    made it.
    """
    params = {
        "kind": kind, "seed": int(seed), "size": [int(size[0]), int(size[1])], "k1": float(k1), "k2": float(k2),
        "centre": [float(centre[0]), float(centre[1])], "noise": float(noise), "blur": float(blur),
        "jpeg_quality": None if jpeg_quality is None else int(jpeg_quality),
        "resize": None if resize is None else float(resize),
    }
    if feather_px is not None:
        params["feather_px"] = float(feather_px)
    return params


def render_authentic(
    seed: int,
    size: tuple[int, int] = (1600, 1200),
    k1: float = 0.08,
    k2: float = 0.0,
    centre: Sequence[float] = (0.0, 0.0),
    *,
    noise: float = 0.01,
    blur: float = 0.7,
    jpeg_quality: int | None = 90,
    resize: float | None = None,
) -> SynthImage:
    """An authentic photo of a random scene.

    Parameters
    ----------
    seed : int
        Determines scene and noise; equal arguments give identical bytes.
    size : (int, int)
        ``(W, H)`` of the camera frame, pixels.
    k1, k2 : float
        Radial distortion (paper eq. 1), normalised coordinates.
    centre : (float, float)
        Centre of distortion, normalised.
    noise : float
        Standard deviation of Gaussian noise, fraction of full scale.
    blur : float
        Optics blur (Gaussian sigma), pixels.
    jpeg_quality : int or None
        Pillow JPEG quality; None keeps the lossless pixels.
    resize : float or None
        Final rescale factor (Lanczos) applied before JPEG.

    Returns
    -------
    SynthImage
    """
    host_rng, noise_rng, _ = seed_streams(seed)
    capture = render_scene(random_scene(host_rng, size), size, k1, k2, centre, blur)
    post = PostProcessing(noise, jpeg_quality, resize)
    pixels, data, _ = finish(capture.image, None, post, noise_rng)
    shape_in = (size[1], size[0])
    return SynthImage(
        image=pixels,
        jpeg_bytes=data,
        mask=None,
        kind="authentic",
        k1=float(k1),
        k2=float(k2),
        centre=capture.centre,
        pasted_k1=None,
        lines_px=[resize_points(p, shape_in, pixels.shape[:2]) for p in capture.lines_px],
        seed=int(seed),
        params=image_params("authentic", seed, size=size, k1=k1, k2=k2, centre=centre, noise=noise, blur=blur,
                            jpeg_quality=jpeg_quality, resize=resize),
    )
