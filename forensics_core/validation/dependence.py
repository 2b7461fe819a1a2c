"""How the detectors' tests depend on each other on authentic photos.

Bonferroni's rule (the default fusion policy) keeps its level whatever the
dependence between detectors; Fisher's combination needs independent tests.
Whether the detectors are independent on real photos is a question of fact:
a recompression or a resize weakens the JPEG grid, the mosaic trace and the
sub-pixel edges at once, so their p-values may move together. This module
measures it on the authentic photos of a suite, pair by pair, with Kendall's
rank correlation of the two p-values over the photos on which both stated a
test, and says whether independence is rejected.

References
----------
M. G. Kendall, A new measure of rank correlation, Biometrika 30 (1938), 81-93.
R. A. Fisher, Statistical Methods for Research Workers, 1925 (the combination
whose validity depends on independence).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import combinations
from typing import Any

import numpy as np

# Independence is called rejected below this two-sided p-value of Kendall's
# test, after Bonferroni over the pairs measured.
INDEPENDENCE_ALPHA = 0.05
# Fewer common photos than this leave the pair unmeasured: Kendall's test
# has no power there and its "no dependence" would say nothing.
MIN_COMMON = 10


@dataclass(frozen=True)
class PairDependence:
    """Rank correlation of two detectors' p-values over the authentic photos where both stated a test.

    ``p_value`` is Kendall's two-sided test of independence; ``rejected``
    whether it is below :data:`INDEPENDENCE_ALPHA` divided by the number of
    pairs measured.
    """

    a: str
    b: str
    n: int
    tau: float | None
    p_value: float | None
    rejected: bool

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> PairDependence:
        return cls(**data)


def pair_dependence(p_values: Sequence[Mapping[str, float]]) -> list[PairDependence]:
    """Kendall's tau for every pair of detectors over the photos on which both stated a test.

    Parameters
    ----------
    p_values : sequence of mapping
        One mapping per authentic photo: detector name to its p-value (or
        ``min(1, NFA)``); detectors that declined on that photo are absent.

    Returns
    -------
    list of PairDependence
        One per pair of detector names, in name order; ``tau`` and
        ``p_value`` None when fewer than :data:`MIN_COMMON` photos hold both
        or either p-value is constant over them.

    Examples
    --------
    >>> rows = [{"a": p, "b": p ** 2} for p in np.linspace(0.05, 1, 12)]
    >>> pair_dependence(rows)[0].tau
    1.0
    """
    names = sorted({n for row in p_values for n in row})
    measured: list[tuple[str, str, int, float | None, float | None]] = []
    for a, b in combinations(names, 2):
        both = [(row[a], row[b]) for row in p_values if a in row and b in row]
        x, y = (np.array(v, dtype=float) for v in zip(*both)) if both else (np.empty(0), np.empty(0))
        if len(both) < MIN_COMMON or np.ptp(x) == 0 or np.ptp(y) == 0:
            measured.append((a, b, len(both), None, None))
            continue
        from scipy.stats import kendalltau  # scipy.stats takes 0.5 s to import: only when measured
        res = kendalltau(x, y)
        measured.append((a, b, len(both), round(float(res.statistic), 4), float(res.pvalue)))
    n_tested = max(1, sum(m[4] is not None for m in measured))
    return [PairDependence(a, b, n, tau, p, p is not None and p < INDEPENDENCE_ALPHA / n_tested)
            for a, b, n, tau, p in measured]


def authentic_dependence(cases: Sequence[Mapping[str, Any]]) -> list[PairDependence]:
    """:func:`pair_dependence` over the authentic photos of a record's per-photo rows.

    Parameters
    ----------
    cases : sequence of mapping
        The record's rows (``spliced``, ``detectors`` with ``status`` and
        ``p_value`` each); photos that could not be taken in are skipped.
    """
    return pair_dependence([{n: d["p_value"] for n, d in c["detectors"].items()
                             if d.get("status") == "ok" and d.get("p_value") is not None}
                            for c in cases if not c["spliced"] and not c.get("error")])
