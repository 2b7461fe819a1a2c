"""Small pictures of the authentic photos a validation run convicted, with the convicting detector's map on them."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from PIL import Image

from ..findings import DetectorFinding, Findings
from ..plugins import PluginHost, localise_map
from .cases import Case
from .null_check import VERDICT, convictions
from .record import ValidationRecord

THUMB_SIDE = 192
"""Longest side of a thumbnail, pixels."""

_TINT = np.array([255.0, 0.0, 0.0])


def write_thumbnail(photo: Path, target: Path, host: PluginHost, finding: DetectorFinding | None) -> Path:
    """Write a downscaled copy of ``photo`` (stored grid, orientation not applied) with ``finding``'s map tinted red.

    The map comes from the finding's detector (its ``localize``) at the
    photo's full size and is box-averaged down, so that a small flagged
    region still shows. ``photo`` is only read.
    """
    with Image.open(photo) as img:
        shape = (img.height, img.width)
        # JPEG: decode at a reduced DCT scale, far cheaper than a full decode.
        img.draft("RGB", (THUMB_SIDE, THUMB_SIDE))
        small = img.convert("RGB")
    small.thumbnail((THUMB_SIDE, THUMB_SIDE), Image.Resampling.BOX)
    rgb = np.asarray(small, dtype=float)
    mask = localise_map(host, finding, shape) if finding is not None else None
    if mask is not None and mask.any():
        cover = np.asarray(Image.fromarray(mask.astype(np.uint8) * 255).resize(small.size, Image.Resampling.BOX)) > 0
        rgb = np.where(cover[..., None], 0.45 * rgb + 0.55 * _TINT, rgb)
    target.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.rint(rgb).astype(np.uint8)).save(target, format="JPEG", quality=80)
    return target


def _finding(findings_file: Path, detector: str) -> DetectorFinding | None:
    if detector == VERDICT or not findings_file.is_file():
        return None
    findings = Findings.from_dict(json.loads(findings_file.read_text(encoding="utf-8")))
    return next((f for f in findings.detectors if f.name == detector), None)


def conviction_thumbnails(record: ValidationRecord, cases: Sequence[Case], findings_dir: Path, host: PluginHost,
                          folder: Path) -> dict[tuple[str, str], Path]:
    """A thumbnail per (photo, detector) of :func:`.null_check.convictions`, written into ``folder``.

    A photo that cannot be read again is left without one.
    """
    paths = {c.name: c.path for c in cases}
    out = {}
    for conv in convictions(record.cases, record.null_checks):
        if conv.case not in paths:
            continue
        target = folder / f"{conv.case}.{conv.detector}.jpg"
        try:
            out[conv.case, conv.detector] = write_thumbnail(
                paths[conv.case], target, host, _finding(findings_dir / f"{conv.case}.json", conv.detector))
        except (OSError, ValueError, Image.DecompressionBombError):
            continue
    return out
