"""Synthetic test photos that plugins contribute for validation.

A plugin that knows how to forge its own trace (a pasted region with another
lens, JPEG grid or CFA phase) returns :class:`SyntheticCase` objects from
``forensics_synthetic_cases``; ``forensics validate synthetic`` runs every
installed detector on every plugin's cases, so each detector is also measured
on the others' forgeries and authentic photos.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class SyntheticCase:
    """One generated photo with its ground truth.

    Parameters
    ----------
    name : str
        Unique among the plugin's cases for one seed, ``[a-z0-9_-]+``; used as a
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


__all__ = ["SyntheticCase"]
