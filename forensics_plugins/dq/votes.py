"""Each block's vote: is its history double or single quantisation?

References
----------
.. [1] T. Bianchi, A. Piva, "Image forgery localization via block-grained
   analysis of JPEG artifacts", IEEE Trans. Information Forensics and
   Security 7(3), 2012, pp. 1003-1017 (eq. 10, the block likelihood map).
"""

from __future__ import annotations

import base64
import zlib
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .primary import BINS, Primary

ACTIVITY_STRATA = 7


def block_log_ratio(quantised: np.ndarray, frequencies: Sequence[tuple[int, int]], primaries: Sequence[Primary]) -> np.ndarray:
    """Sum over the chosen frequencies of log p_D(x) / p_S(x), shape (h, w), nats.

    Parameters
    ----------
    quantised : ndarray of int, shape (h, w, 8, 8)
    frequencies : sequence of (row, column)
    primaries : sequence of Primary, one per frequency
    """
    total = np.zeros(quantised.shape[:2])
    for (i, j), p in zip(frequencies, primaries):
        ratio = np.log(p.p_double / p.p_single)
        total += ratio[np.clip(quantised[:, :, i, j], -BINS, BINS) + BINS]
    return total


def activity(quantised: np.ndarray) -> np.ndarray:
    """Stratum of each block by its number of non-zero AC coefficients (log2 bins 0..6), shape (h, w)."""
    nonzero = (quantised.reshape(*quantised.shape[:2], 64)[:, :, 1:] != 0).sum(axis=-1)
    return np.minimum(np.log2(nonzero + 1).astype(int), ACTIVITY_STRATA - 1)


def null_rates(informative: np.ndarray, single: np.ndarray, strata: np.ndarray) -> np.ndarray:
    """Per block, the photo's own rate of "single" votes among informative blocks of its stratum, shape (h, w).

    Textured blocks vote more decisively than nearly flat ones, so the rate a
    region is compared with is that of blocks of the same activity over the
    whole photo (a pasted region included, which only makes the test more
    cautious). Laplace's rule keeps rates off 0 and 1.
    """
    rates = np.array([(single[informative & (strata == s)].sum() + 1.0) / ((informative & (strata == s)).sum() + 2.0)
                      for s in range(ACTIVITY_STRATA)])
    return rates[strata]


VOTE_ENCODING = "zlib-compressed uint8 per block, row-major, base64: 0 undecided, 1 double, 2 single"


def encode_votes(informative: np.ndarray, single: np.ndarray) -> dict[str, Any]:
    """The block votes as the finding carries them, so that the report draws them without recomputing.

    Parameters
    ----------
    informative, single : ndarray of bool, shape (h, w)

    Returns
    -------
    dict
        ``shape`` (h, w), ``encoding`` (:data:`VOTE_ENCODING`) and ``data``;
        a few kB to tens of kB, since the votes come in runs.
    """
    codes = np.where(informative, np.where(single, 2, 1), 0).astype(np.uint8)
    return {"shape": list(codes.shape), "encoding": VOTE_ENCODING,
            "data": base64.b64encode(zlib.compress(codes.tobytes(), 9)).decode("ascii")}


def decode_votes(record: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """``(informative, single)``, each bool of shape (h, w), from :func:`encode_votes`'s record.

    Raises
    ------
    ValueError
        When the record does not hold as many votes as its shape says.
    """
    h, w = (int(v) for v in record["shape"])
    codes = np.frombuffer(zlib.decompress(base64.b64decode(record["data"])), np.uint8)
    if codes.size != h * w:
        raise ValueError(f"the block votes hold {codes.size} values for a {h} x {w} map")
    codes = codes.reshape(h, w)
    return codes > 0, codes == 2
