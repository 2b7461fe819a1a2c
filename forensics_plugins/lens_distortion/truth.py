"""The truth a synthetic photo carries, and the files it is written to.

Every output carries its truth: the straight edges of the host, and of the
pasted part, as distorted polylines in pixels, the paste mask, and the
parameters that regenerate it (:func:`.splice.generate`). :func:`write` puts
the photo, its mask and its truth on disk, as ``forensics synth`` does.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image


@dataclass(frozen=True, eq=False)
class PasteTruth:
    """What was pasted, where from, and what it carries.

    Output pixels ``p`` of the region come from source pixels
    ``source_centre_px + (p - target_centre_px) / scale`` of the source
    capture (both in pixels of the unresized frame).

    Attributes
    ----------
    source_k1, source_k2 : float
        Distortion of the camera the pasted pixels come from (normalised
        coordinates of the source frame).
    scale : float
        Magnification applied to the pasted part (1 for copy-move and other camera).
    source_centre_px, target_centre_px : tuple of float
        Region centres in the source capture and in the output, pixels of the
        unresized frame.
    region_px : ndarray, shape (4, 2)
        Outline of the pasted region in output pixels (after any resize).
    lines_px : list of ndarray, each (N_i, 2)
        Straight 3-D edges inside the pasted part, output pixels (after any resize).
    source_lines_px : list of ndarray, each (N_i, 2)
        The same edges in pixels of the source capture; they are straight
        after undistortion with ``source_k1`` in the source frame.
    """

    source_k1: float
    source_k2: float
    scale: float
    source_centre_px: tuple[float, float]
    target_centre_px: tuple[float, float]
    region_px: np.ndarray
    lines_px: list[np.ndarray]
    source_lines_px: list[np.ndarray]


@dataclass(frozen=True, eq=False)
class SynthImage:
    """A synthetic photo with its truth.

    Attributes
    ----------
    image : ndarray, shape (H, W, 3), uint8
        Final pixels (JPEG-decoded when ``jpeg_bytes`` is set).
    jpeg_bytes : bytes or None
        The encoded file when a JPEG quality was set: what a user would analyse.
    mask : ndarray, shape (H, W), bool, or None
        True on pixels that received any pasted content; None when authentic.
    kind : str
        One of :data:`.spec.KINDS`.
    k1, k2 : float
        Host camera distortion (normalised coordinates).
    centre : tuple of float
        Host centre of distortion, normalised.
    pasted_k1 : float or None
        Distortion of the camera the pasted part comes from; None for
        authentic and copy-move (whose pasted part is the host's own, moved).
    lines_px : list of ndarray, each (N_i, 2)
        The host's visible straight 3-D edges as distorted polylines, pixels
        of the final image; for a splice, only the parts outside the mask.
    seed : int
    params : dict
        Flat JSON-able arguments that regenerate the image with :func:`.splice.generate`.
    paste : PasteTruth or None
    """

    image: np.ndarray
    jpeg_bytes: bytes | None
    mask: np.ndarray | None
    kind: str
    k1: float
    k2: float
    centre: tuple[float, float]
    pasted_k1: float | None
    lines_px: list[np.ndarray]
    seed: int
    params: dict = field(default_factory=dict)
    paste: PasteTruth | None = None


def _polylines_json(lines: list[np.ndarray]) -> list[list[list[float]]]:
    # 1e-4 px is far below any detector's precision and keeps the files small.
    return [np.round(p, 4).tolist() for p in lines]


def truth_record(img: SynthImage) -> dict:
    """JSON-able truth of one image: camera, splice and the straight edges."""
    record = {
        "kind": img.kind,
        "seed": img.seed,
        "k1": img.k1,
        "k2": img.k2,
        "centre": list(img.centre),
        "pasted_k1": img.pasted_k1,
        "size": [int(img.image.shape[1]), int(img.image.shape[0])],
        "params": img.params,
        "lines_px": _polylines_json(img.lines_px),
    }
    if img.paste is not None:
        p = img.paste
        record["paste"] = {
            "source_k1": p.source_k1,
            "source_k2": p.source_k2,
            "scale": p.scale,
            "source_centre_px": list(p.source_centre_px),
            "target_centre_px": list(p.target_centre_px),
            "region_px": np.round(p.region_px, 4).tolist(),
            "lines_px": _polylines_json(p.lines_px),
            "source_lines_px": _polylines_json(p.source_lines_px),
        }
    return record


def write(img: SynthImage, out_dir: Path, stem: str) -> list[Path]:
    """Write the photo, its mask and its truth.

    The photo is ``stem.jpg`` (the encoded bytes) or, without JPEG, the
    lossless ``stem.png``; the mask ``stem_mask.png`` (255 on pasted pixels);
    the truth ``stem.json`` (:func:`truth_record`).

    Returns
    -------
    list of Path
        Photo, mask (splices only) and truth files, in that order.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if img.jpeg_bytes is not None:
        photo = out_dir / f"{stem}.jpg"
        photo.write_bytes(img.jpeg_bytes)
    else:
        photo = out_dir / f"{stem}.png"
        Image.fromarray(img.image).save(photo)
    paths = [photo]
    if img.mask is not None:
        mask_path = out_dir / f"{stem}_mask.png"
        Image.fromarray(img.mask.astype(np.uint8) * 255).save(mask_path)
        paths.append(mask_path)
    truth = out_dir / f"{stem}.json"
    truth.write_text(json.dumps(truth_record(img), separators=(",", ":"), sort_keys=True) + "\n")
    paths.append(truth)
    return paths
