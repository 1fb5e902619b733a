"""Confidence intervals of a sample's percentiles, distribution-free (``docs/studies.md``, "Analysis").

The p-th percentile of a population lies between the sample's order statistics of ranks ``l`` and ``u`` with a
probability the binomial distribution gives exactly, whatever the population: the number of sample values below the
percentile is Binomial(n, p). :func:`percentile_interval` takes the ranks between its 2.5 % and 97.5 % points, a
95 % interval (conservative: at least 95 %).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.stats import binom, binomtest

__all__ = ["CONFIDENCE", "exceedance", "percentile_interval"]

#: The intervals' confidence level.
CONFIDENCE = 0.95


def percentile_interval(ordered: NDArray, level: float) -> tuple[float, float]:
    """The 95 % interval of the ``level``-th percentile (0-100) from a sorted sample ``ordered`` (module
    docstring); an end that no order statistic bounds with that confidence (a sample too small for its tail: fewer
    than about 3.7 / p values for the p-th percentile's lower end) is infinite."""
    n = len(ordered)
    q = level / 100.0
    tail = 0.5 * (1.0 - CONFIDENCE)
    below = int(binom.ppf(tail, n, q))  # the smallest k with P(B <= k) >= tail, B ~ Binomial(n, q)
    above = int(binom.ppf(1.0 - tail, n, q))
    low = -np.inf if below == 0 else float(ordered[below - 1])  # P(B <= below - 1) < tail
    high = np.inf if above >= n else float(ordered[above])  # P(B >= above + 1) <= tail
    return low, high


def exceedance(values: NDArray, above: float) -> dict[str, float | int]:
    """How many of ``values`` (finite ones; NaN: not counted) exceed the limit ``above``: their count, the number
    counted, the fraction and its 95 % Clopper-Pearson interval (exact, from the binomial), and the yield (the
    fraction within the limit) with its interval."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    n, k = int(v.size), int(np.sum(v > above))
    if n == 0:
        return {"above": float(above), "n": 0, "exceeding": 0}
    low, high = binomtest(k, n).proportion_ci(confidence_level=CONFIDENCE, method="exact")
    return {
        "above": float(above),
        "n": n,
        "exceeding": k,
        "fraction": k / n,
        "fraction_low": float(low),
        "fraction_high": float(high),
        "yield": 1.0 - k / n,
        "yield_low": 1.0 - float(high),
        "yield_high": 1.0 - float(low),
    }
