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
_SIMULATED_VALUES = 2_000_000  # values simulated at once, all candidate steps together


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


def _histograms(values: np.ndarray) -> np.ndarray:
    """Each row's distribution of quantised values, shape (k, 2 BINS + 1), with half a count added to every value.

    ``values`` has shape (k, n), integers; values beyond ``BINS`` are pooled at the ends.
    """
    k = values.shape[0]
    width = 2 * BINS + 1
    index = np.clip(values, -BINS, BINS) + BINS + width * np.arange(k)[:, None]
    counts = np.bincount(index.ravel(), minlength=k * width).reshape(k, width).astype(np.float64) + 0.5
    return counts / counts.sum(axis=1, keepdims=True)


def _mixture(counts: np.ndarray, p_double: np.ndarray, p_single: np.ndarray,
             iterations: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """EM for the share ``alpha`` of each row of ``p_double`` (k, bins) against ``p_single`` (bins,), all rows at once.

    Returns ``alpha`` and the gain in log-likelihood over ``p_single``, each shape (k,).
    """
    alpha = np.full((p_double.shape[0], 1), 0.5)
    for _ in range(iterations):
        share = alpha * p_double / (alpha * p_double + (1 - alpha) * p_single)
        alpha = ((counts * share).sum(axis=1) / counts.sum())[:, None]
    gain = (counts * (np.log(alpha * p_double + (1 - alpha) * p_single) - np.log(p_single))).sum(axis=1)
    return alpha[:, 0], gain


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
    originals of the shared corpus it did). All candidate steps are simulated
    and fitted at once; the first of equal gains is kept.
    """
    counts = np.bincount(np.clip(observed, -BINS, BINS) + BINS, minlength=2 * BINS + 1).astype(np.float64)
    p_single = _histograms(np.round(unquantised / q2).astype(np.int64)[None, :])[0]
    noise = rng.normal(0.0, _ROUNDING_SD, unquantised.size)
    steps = np.arange(q2 + 1, 3 * q2 + 13)
    # Simulated a few steps at a time, so that memory stays near a few times
    # the coefficients' own whatever the number of steps (2 q2 + 12, over 500
    # for a quality-1 table).
    chunk = max(1, _SIMULATED_VALUES // max(unquantised.size, 1))
    p_double = np.concatenate([
        _histograms(np.round((np.round(unquantised / q1) * q1 + noise) / q2).astype(np.int64))
        for q1 in (steps[i: i + chunk, None].astype(np.float64) for i in range(0, len(steps), chunk))])
    alpha, gain = _mixture(counts, p_double, p_single)
    best = int(np.argmax(gain))
    if not gain[best] > 0:
        return None
    return Primary(int(steps[best]), q2, float(alpha[best]), float(gain[best]), p_double[best], p_single)
