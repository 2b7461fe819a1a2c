"""How often each check calls an authentic camera original "suspicious", as measured.

``real_rates.json`` is written by ``benchmarks/metadata_real.py --write``
from a corpus of authentic camera originals (the corpus itself is not
shipped: only its description, the counts and the date). The report quotes
the rate next to each check, so a reader sees how often the check is wrong
on photos nobody touched.
"""

from __future__ import annotations

import json
from functools import cache
from importlib.resources import files
from typing import Any

# scipy.special, not scipy.stats: the beta quantile is the same function
# (identical values for every k < n < 800), and scipy.stats takes half a
# second to import in the report section's child.
from scipy.special import betaincinv

RATES_FILE = "real_rates.json"


@cache
def measured_rates() -> dict[str, Any] | None:
    """The shipped measurement, or None when the file is absent or unreadable."""
    try:
        return json.loads(files(__package__).joinpath(RATES_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def rate_sentence(check_id: str) -> str | None:
    """One sentence giving the check's false-alarm rate on camera originals, or None when not measured.

    The one-sided 95 % Clopper-Pearson upper bound is given with it: a few
    dozen originals cannot show a rate much below a few per cent.

    Parameters
    ----------
    check_id : str
        :attr:`.checks.Check.id`.

    References
    ----------
    C. J. Clopper, E. S. Pearson, The use of confidence or fiducial limits illustrated in the case of the binomial,
    Biometrika 26(4), 404-413, 1934.
    """
    rates = measured_rates()
    row = None if rates is None else rates.get("checks", {}).get(check_id)
    if row is None:
        return None
    k, n = int(row["suspicious"]), int(row["applicable"])
    if n == 0:
        return f"This check applied to none of the {rates['n_photos']} camera originals measured."
    upper = 1.0 if k >= n else float(betaincinv(k + 1, n - k, 0.95))
    return (f"This check flags {100 * k / n:.1f}% of camera originals ({k} of the {n} it applied to; at most "
            f"{100 * upper:.1f}% at 95% confidence).")


def corpus_sentence() -> str | None:
    """Where and when the rates were measured, or None when they were not."""
    rates = measured_rates()
    if rates is None:
        return None
    return (f"The false-alarm rates quoted with each check were measured {rates['measured']} with detector version "
            f"{rates['detector_version']} on {rates['corpus']}.")
