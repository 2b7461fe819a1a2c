"""Binomial tails and intervals for the a-contrario tests (vectorised, in log10).

The upper tail ``P(Bin(n, p) >= k)`` is the regularised incomplete beta
function ``I_p(k, n - k + 1)``; where it underflows double precision it is
replaced by the Chernoff-Hoeffding bound ``exp(-n KL(k/n || p))``
(Hoeffding, 1963, eq. 2.1), which is larger than the tail, so a test using it
stays conservative.
"""

from __future__ import annotations

import numpy as np
from scipy import special

_LOG10_E = np.log10(np.e)


def _kl(q: np.ndarray, p: float) -> np.ndarray:
    """Kullback-Leibler divergence of Bernoulli(q) from Bernoulli(p), nats; 0 log 0 = 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(q > 0, q * np.log(q / p), 0.0)
        b = np.where(q < 1, (1 - q) * np.log((1 - q) / (1 - p)), 0.0)
    return a + b


def log10_chernoff(k: np.ndarray, n: np.ndarray, p: float | np.ndarray) -> np.ndarray:
    """Chernoff-Hoeffding upper bound of ``log10 P(Bin(n, p) >= k)``; 0 where ``k <= n p`` (``p`` broadcasts)."""
    k = np.asarray(k, dtype=np.float64)
    n = np.asarray(n, dtype=np.float64)
    q = np.divide(k, n, out=np.zeros_like(k), where=n > 0)
    return np.where(k > n * p, -n * _kl(q, p) * _LOG10_E, 0.0)


def log10_binom_tail(k: np.ndarray, n: np.ndarray, p: float | np.ndarray) -> np.ndarray:
    """``log10 P(Bin(n, p) >= k)`` for arrays of counts, exact unless it underflows.

    Parameters
    ----------
    k, n : array_like of int
        Successes and trials (broadcast together), ``0 <= k <= n``.
    p : float or array_like
        Success probability under the null hypothesis, in (0, 1) (broadcast
        with ``k`` and ``n``).

    Returns
    -------
    ndarray of float64
        At most 0; where the exact tail underflows, the (larger) Chernoff bound.
    """
    k = np.asarray(k, dtype=np.float64)
    n = np.asarray(n, dtype=np.float64)
    k, n, p = np.broadcast_arrays(k, n, np.asarray(p, dtype=np.float64))
    out = np.zeros(k.shape)
    pos = k > 0
    if pos.any():
        tail = special.betainc(k[pos], n[pos] - k[pos] + 1.0, p[pos])
        with np.errstate(divide="ignore"):
            exact = np.log10(tail)
        bound = log10_chernoff(k[pos], n[pos], p[pos])
        out[pos] = np.where(tail > 1e-290, exact, bound)
    return out


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple[float | None, float | None]:
    """Exact two-sided confidence interval of a binomial proportion; (None, None) when ``n == 0``."""
    if n <= 0:
        return None, None
    a = 1.0 - level
    # Beta quantiles by scipy.special (what scipy.stats.beta.ppf calls), sparing every run scipy.stats' import.
    lo = 0.0 if k == 0 else float(special.betaincinv(k, n - k + 1, a / 2))
    hi = 1.0 if k == n else float(special.betaincinv(k + 1, n - k, 1 - a / 2))
    return lo, hi
