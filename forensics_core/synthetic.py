"""Synthetic test photos that plugins contribute for validation.

A detector that knows how to forge its own trace (a pasted region with another
lens, JPEG grid or CFA phase) returns :class:`SyntheticCase` objects from
its ``synthetic_cases``; ``forensics validate synthetic`` runs every
installed detector on every detector's cases, so each detector is also measured
on the others' forgeries and authentic photos.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from PIL import Image


@dataclass(frozen=True)
class SyntheticCase:
    """One generated photo with its ground truth.

    Parameters
    ----------
    name : str
        Unique among the detector's cases for one seed, ``[a-z0-9_-]+``; used as a
        file stem.
    data : bytes
        The encoded file exactly as it is to be examined.
    suffix : str
        File suffix matching ``data``: ``".jpg"``, ``".png"`` or ``".tif"``.
    spliced : bool
        True when part of the photo was pasted from another source.
    mask : numpy.ndarray or None
        Boolean, shape ``(H, W)`` of the stored grid, True on pasted pixels;
        None for authentic photos or when unknown.
    conditions : mapping of str to str
        Tags for per-condition error rates, e.g. ``{"kind": "shifted_grid",
        "jpeg_quality": "85", "size": "1024x768"}``. Use ``kind`` for the kind
        of splice (``"none"`` for authentic photos).
    """

    name: str
    data: bytes
    suffix: str
    spliced: bool
    mask: np.ndarray | None = None
    conditions: Mapping[str, str] = field(default_factory=dict)


def grey_shapes(rng: np.random.Generator, size: tuple[int, int]) -> np.ndarray:
    """A noiseless grey scene: smooth shading and 12 filled ellipses, blurred by 1.2 px.

    A base for plugins' synthetic photos; a plugin adds the trace it
    studies (grain, quantisation, a pasted piece).

    Parameters
    ----------
    rng : numpy.random.Generator
    size : (int, int)
        Width, height in pixels.

    Returns
    -------
    ndarray of float32, shape (height, width)
        Grey levels, about 30-220.
    """
    import cv2

    w, h = size
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    img = 90 + 60 * np.sin(x / rng.uniform(80, 200) + rng.uniform(0, 6)) * np.cos(y / rng.uniform(80, 200))
    for _ in range(12):
        centre = (int(rng.integers(0, w)), int(rng.integers(0, h)))
        axes = (int(rng.integers(20, 140)), int(rng.integers(20, 140)))
        cv2.ellipse(img, centre, axes, float(rng.uniform(0, 180)), 0, 360, float(rng.uniform(30, 220)), -1)
    return cv2.GaussianBlur(img, (0, 0), 1.2)


def paste_ellipse(host: np.ndarray, donor: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The host with an ellipse of the donor pasted in the photo's central half, and the ellipse's mask.

    Parameters
    ----------
    host, donor : ndarray, shape (H, W)
    rng : numpy.random.Generator
        Draws the centre and the semi-axes (60-159 px across, 60-139 px down).

    Returns
    -------
    image : ndarray, shape (H, W)
    mask : ndarray of bool, shape (H, W)
        True on pasted pixels.
    """
    import cv2

    h, w = host.shape
    mask = np.zeros((h, w), np.uint8)
    centre = (int(rng.integers(w // 4, 3 * w // 4)), int(rng.integers(h // 4, 3 * h // 4)))
    cv2.ellipse(mask, centre, (int(rng.integers(60, 160)), int(rng.integers(60, 140))), 0, 0, 360, 1, -1)
    pasted = mask.astype(bool)
    out = host.copy()
    out[pasted] = donor[pasted]
    return out, pasted


def grey_jpeg(img: np.ndarray, quality: int) -> bytes:
    """JPEG bytes of a grey image, with libjpeg's standard tables at ``quality``.

    Parameters
    ----------
    img : ndarray, shape (H, W)
        Grey levels, 0-255; rounded and clipped to 8 bits.
    quality : int
        libjpeg quality, 1-100.
    """
    buf = io.BytesIO()
    Image.fromarray(np.clip(np.round(img), 0, 255).astype(np.uint8)).save(buf, format="JPEG", quality=quality)
    return buf.getvalue()


__all__ = ["SyntheticCase", "grey_jpeg", "grey_shapes", "paste_ellipse"]
