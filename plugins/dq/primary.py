"""The earlier (primary) quantisation step of each DCT frequency, estimated from the coefficient histogram.

Under aligned double compression a coefficient was first quantised with
step ``q1``, decoded (rounding the pixels adds noise of variance 1/12 grey
level squared to each orthonormal DCT coefficient), then quantised with the
stored step ``q2``: ``x = round((q1 round(u / q1) + e) / q2)``. Under single
compression ``x = round(u / q2)``. Both histograms are simulated from the
calibrated coefficients ``u`` (:func:`.coefficients.calibrated`) instead of
being approximated analytically ([1]_ eq. 5-8), and the observed histogram is
fitted as the mixture ``alpha p_D + (1 - alpha) p_S`` by EM.

References
----------
.. [1] T. Bianchi, A. Piva, "Image forgery localization via block-grained
   analysis of JPEG artifacts", IEEE Trans. Information Forensics and
   Security 7(3), 2012, pp. 1003-1017.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BINS = 80  # histogram over quantised values -BINS..BINS (larger ones pooled at the ends)
_ROUNDING_SD = np.sqrt(1.0 / 12.0)


@dataclass(frozen=True)
class Primary:
    """The primary step that best explains one frequency's histogram.

    Attributes
    ----------
    q1, q2 : int
        Primary step found and the stored step.
    alpha : float
        Fitted share of coefficients drawn from the double-compression model.
    log_lik : float
        Gain in log-likelihood (nats) of the mixture over single compression.
    p_double, p_single : ndarray, shape (2 BINS + 1,)
        The two models' probabilities of each quantised value.
    """

    q1: int
    q2: int
    alpha: float
    log_lik: float
    p_double: np.ndarray
    p_single: np.ndarray


def _histogram(values: np.ndarray) -> np.ndarray:
    counts = np.bincount(np.clip(values, -BINS, BINS) + BINS, minlength=2 * BINS + 1).astype(np.float64) + 0.5
    return counts / counts.sum()


def _mixture(counts: np.ndarray, p_double: np.ndarray, p_single: np.ndarray, iterations: int = 40) -> tuple[float, float]:
    alpha = 0.5
    for _ in range(iterations):
        share = alpha * p_double / (alpha * p_double + (1 - alpha) * p_single)
        alpha = float((counts * share).sum() / counts.sum())
    gain = float((counts * (np.log(alpha * p_double + (1 - alpha) * p_single) - np.log(p_single))).sum())
    return alpha, gain


def estimate(observed: np.ndarray, unquantised: np.ndarray, q2: int, rng: np.random.Generator) -> Primary | None:
    """The primary step of one frequency, or None when no step above ``q2`` improves on single compression.

    Parameters
    ----------
    observed : ndarray of int, shape (n,)
        The stored quantised values of this frequency over reliable blocks.
    unquantised : ndarray of float, shape (m,)
        Calibrated coefficients of this frequency (grey levels).
    q2 : int
        The stored quantisation step.
    rng : numpy.random.Generator
        Source of the simulated rounding noise (seeded: the same photo gives
        the same estimate).

    Notes
    -----
    Only steps ``q1 > q2`` are sought: they leave near-empty values in the
    histogram, a signature that smooth content cannot imitate; ``q1 < q2``
    leaves a periodic ripple that the calibration's own error can (on camera
    originals of the shared corpus it did).
    """
    counts = np.bincount(np.clip(observed, -BINS, BINS) + BINS, minlength=2 * BINS + 1).astype(np.float64)
    p_single = _histogram(np.round(unquantised / q2).astype(np.int64))
    noise = rng.normal(0.0, _ROUNDING_SD, unquantised.size)
    best: Primary | None = None
    for q1 in range(q2 + 1, 3 * q2 + 13):
        p_double = _histogram(np.round((np.round(unquantised / q1) * q1 + noise) / q2).astype(np.int64))
        alpha, gain = _mixture(counts, p_double, p_single)
        if gain > 0 and (best is None or gain > best.log_lik):
            best = Primary(q1, q2, alpha, gain, p_double, p_single)
    return best
