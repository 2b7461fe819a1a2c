"""Binomial tails in log10, for the a-contrario tests.

The number of false alarms of a count ``k`` out of ``n`` trials with success
probability ``p`` under the null hypothesis is ``N_tests * P[X >= k]``,
``X ~ B(n, p)`` (Desolneux, Moisan, Morel, "From Gestalt Theory to Image
Analysis", Springer 2008; as used by ZERO, Nikoukhah et al. 2019). Strong JPEG
traces give tails far below the smallest double, so everything is in log10.
"""

from __future__ import annotations

import math

from scipy import special

_LN10 = math.log(10.0)


def log10_binomial_tail(n: float, k: float, p: float) -> float:
    """``log10 P[X >= k]`` for ``X ~ B(n, p)``; trials and successes are floored to integers.

    Where the exact tail underflows, the first term of the tail divided by
    ``1 - r`` (``r`` the ratio of consecutive terms, which only decreases past
    the mode) is returned: an upper bound, so a conservative NFA.
    """
    n = math.floor(max(n, 0.0))
    k = math.floor(k)
    if k <= 0:
        return 0.0
    if k > n:
        return -math.inf if p < 1.0 else 0.0
    if p <= 0.0:
        return -math.inf
    if p >= 1.0:
        return 0.0
    # P(X >= k) for X ~ B(n, p) is the regularised incomplete beta I_p(k, n - k + 1): the routine
    # scipy.stats.binom.sf calls, without the 0.4 s that importing scipy.stats adds to every run.
    sf = float(special.betainc(k, n - k + 1, p))
    exact = math.log(sf) if sf > 0.0 else -math.inf
    if math.isfinite(exact) and exact > -700.0:
        return min(0.0, exact / _LN10)
    log_term = (special.gammaln(n + 1) - special.gammaln(k + 1) - special.gammaln(n - k + 1)
                + k * math.log(p) + (n - k) * math.log1p(-p))
    ratio = (n - k) / (k + 1) * p / (1.0 - p)
    bound = log_term - math.log1p(-ratio) if ratio < 1.0 else log_term + math.log(n - k + 1)
    return min(0.0, bound / _LN10)


def finite_log10(value: float, floor: float = -1000.0) -> float:
    """``value`` clipped below at ``floor`` so it can be written as JSON (log10 NFA of a huge trace)."""
    return max(floor, value)


def nfa_text(log10_nfa: float) -> str:
    """An NFA for a reader: plain below a thousand-fold either way, else a power of ten (the floor as a bound)."""
    if log10_nfa <= -1000.0:
        return "< 10^-1000"
    if -3.0 <= log10_nfa <= 3.0:
        return f"{10.0 ** log10_nfa:.2g}"
    return f"10^{log10_nfa:.1f}"
