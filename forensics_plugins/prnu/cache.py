"""Fingerprints kept between runs: one per reference set, named by the set's hashes and the estimator.

Estimating a fingerprint costs seconds per reference photo; a folder of
photos checked against one camera reuses it. The cache holds only what the
references determine (the same bytes and parameters give the same array),
so a cached fingerprint is the one the run would estimate.
"""

from __future__ import annotations

import hashlib
import io
import os
from pathlib import Path

import numpy as np

from forensics_core import ReferenceSet

from .fingerprint import Fingerprint, estimate
from .residual import eight_bit
from .spec import VERSION

CACHE_ENV = "FORENSICS_CACHE"


def cache_dir() -> Path:
    """``$FORENSICS_CACHE/prnu``, else ``$XDG_CACHE_HOME/forensics/prnu``, else ``~/.cache/forensics/prnu``."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV]) / "prnu"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "forensics" / "prnu"


def _oriented(reference: ReferenceSet) -> list[np.ndarray]:
    """The references' pixels, those with swapped sides turned to the first one's orientation.

    Raises
    ------
    ValueError
        When the references are not all of one size.
    """
    first = reference.photos[0].pixels.shape[:2]
    out = []
    for photo in reference.photos:
        pixels = photo.pixels
        if pixels.shape[:2] == first[::-1] and first[0] != first[1]:
            pixels = np.rot90(pixels)
        if pixels.shape[:2] != first:
            raise ValueError(f"the reference photos differ in size ({first[1]}x{first[0]} and "
                             f"{photo.info.width}x{photo.info.height}, {photo.info.name}); a fingerprint needs "
                             f"photos of one camera at one resolution")
        out.append(eight_bit(pixels))
    return out


def fingerprint_for(reference: ReferenceSet, sigma0: float) -> tuple[Fingerprint, bool]:
    """The fingerprint of ``reference``, from the cache when it holds it; and whether it did.

    Raises
    ------
    ValueError
        As :func:`_oriented`.
    """
    key = hashlib.sha256(f"{reference.digest}|{VERSION}|{sigma0!r}".encode()).hexdigest()[:32]
    path = cache_dir() / f"{key}.npz"
    try:
        with np.load(path) as stored:
            return Fingerprint(stored["k"], int(stored["count"])), True
    except (OSError, KeyError, ValueError):
        pass
    fingerprint = estimate(_oriented(reference), sigma0)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        buffer = io.BytesIO()
        np.savez(buffer, k=fingerprint.k, count=fingerprint.count)
        temporary = path.with_suffix(f".{os.getpid()}.tmp")
        temporary.write_bytes(buffer.getvalue())
        os.replace(temporary, path)
    except OSError:
        pass
    return fingerprint, False
