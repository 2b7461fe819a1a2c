"""Does the repetition go on? What tells a copy from a printed or manufactured pattern.

A copy-move makes one more instance of a region: the target ``T = M(S)`` of
its source ``S`` under the transform ``M``. A printed or manufactured pattern
(wallpaper, tiles, a mesh, a row of identical products) repeats under one
transform again and again, and every instance is the same print, so it
shares its fine grain as a copy does (:mod:`.identity`). What tells them
apart is whether the repetition goes on. Where a pattern continues, the
transform applied once more maps grain onto grain as well: ``M(T)`` repeats
``T``, and ``S`` repeats ``M^-1(S)``. Past a copy and before its source lies
whatever the scene holds there, whose grain is the scene's own.

The *lattice peak* of a candidate is the grain peak (:func:`.identity.identity`,
aligned as the candidate is, :func:`.identity.best_alignment`) of the step
past the target and of the step before the source, the smaller of the two
where both lie in the photo and hold grain, the one that does otherwise, and
0 when neither does or when it is negative. A repetition that goes on
wherever it can be seen is a pattern; the candidate's evidence of a copy is
its grain peak less its lattice peak, the *net peak*.

Measured on the shared real corpus, a photo's largest net peak differs from
its largest grain peak by more than 0.01 on no MICC-F220 or IMD copy-move,
and on five authentic photos: the printed wallpaper (one file, in the set
under two names) from 0.27 to 0.05, and three MICC-F220 originals whose
peaks were below 0.1 (repeated structure) to 0.05 or less. Outside the
corpus, the honeycomb mesh of a car's grille in an authentic camera photo
went from 0.35 to 0.18 (lattice peak 0.17). It does not see repetition that
does not go on under the same transform: two prints of one picture, a column
of windows whose size changes with depth from one to the next, the branches
of an artificial fir (lattice peaks below 0, or the step leaves the photo).
And it cannot see a copy moved along a printed pattern by the pattern's own
period (a tile of wallpaper cloned over its neighbour), which is a pattern to
this test.

References
----------
.. [1] I. Amerini, L. Ballan, R. Caldelli, A. Del Bimbo, G. Serra, A SIFT-based
   forensic method for copy-move attack detection and transformation recovery,
   IEEE TIFS 6(3), 2011 (the transform between a copy and its source).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import cv2
import numpy as np

from .identity import best_alignment
from .transforms import Hypothesis


def _moved(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``points`` (shape (n, 2)) mapped by the affine ``matrix`` (shape (2, 3))."""
    return points @ matrix[:, :2].T + matrix[:, 2]


def lattice_peaks(gray: np.ndarray, grain: np.ndarray, hypothesis: Hypothesis,
                  params: Mapping[str, Any]) -> tuple[float | None, float | None]:
    """Grain peaks of the candidate's transform one step further on: past the target, and before the source.

    Parameters
    ----------
    gray : ndarray, shape (h, w)
        Work image, 0-255.
    grain : ndarray, shape (h, w)
        :func:`.identity.residual` of ``gray``.
    hypothesis : Hypothesis
        The candidate as aligned, ``target = matrix @ (source, 1)``.
    params : mapping
        The detector's parameters (window, minimum distance, refinement).

    Returns
    -------
    past_target, before_source : float or None
        The grain peak of ``T`` against ``M(T)`` and of ``M^-1(S)`` against
        ``S``; None where the step leaves the photo or holds no grain.
    """
    back = cv2.invertAffineTransform(hypothesis.matrix)
    steps = (Hypothesis(hypothesis.matrix, hypothesis.target, _moved(hypothesis.matrix, hypothesis.target)),
             Hypothesis(hypothesis.matrix, _moved(back, hypothesis.source), hypothesis.source))
    peaks = []
    for step in steps:
        _, found, _ = best_alignment(gray, grain, step, params)
        peaks.append(None if found is None else found.peak)
    return peaks[0], peaks[1]


def lattice_peak(peaks: tuple[float | None, float | None]) -> float:
    """The grain peak the pattern keeps one step further (module docstring): the smaller seen, at least 0."""
    seen = [p for p in peaks if p is not None]
    return max(0.0, min(seen)) if seen else 0.0
