"""The lens plugin's synthetic cases for ``forensics validate synthetic`` (``LensDistortion.synthetic_cases``).

Authentic photos (:mod:`.photo`) and splices of the paper's three kinds
(:mod:`.splice`), each with its own lens, size and JPEG quality.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from forensics_core import SyntheticCase

from .splice import SPLICE_KINDS, make_splice

_CASE_SIZES = ((1200, 900), (1600, 1200))
_CASE_QUALITIES = (75, 85, 95)


def validation_cases(seed: int, count: int) -> Iterator[SyntheticCase]:
    """``count`` authentic and ``count`` spliced photos for ``forensics validate``.

    Each case draws its host lens (``|k1|`` in [0.03, 0.15], either sign),
    size and JPEG quality from ``(seed, i)``; splices cycle through the
    paper's three kinds. Conditions: ``kind``, ``jpeg_quality``, ``size``.
    """
    for i in range(count):
        for spliced in (False, True):
            rng = np.random.default_rng([seed, i, int(spliced)])
            k1 = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.03, 0.15))
            size = _CASE_SIZES[int(rng.integers(len(_CASE_SIZES)))]
            quality = int(_CASE_QUALITIES[int(rng.integers(len(_CASE_QUALITIES)))])
            kind = SPLICE_KINDS[i % len(SPLICE_KINDS)] if spliced else "authentic"
            case_seed = int(rng.integers(2**31))
            img = make_splice(kind, case_seed, size=size, k1=k1, jpeg_quality=quality)
            yield SyntheticCase(
                name=f"lens-{kind.replace('_', '-')}-{i:03d}",
                data=img.jpeg_bytes,
                suffix=".jpg",
                spliced=spliced,
                mask=img.mask,
                conditions={"kind": kind if spliced else "none", "jpeg_quality": str(quality),
                            "size": f"{size[0]}x{size[1]}"},
            )
