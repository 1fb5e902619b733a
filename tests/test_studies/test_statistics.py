"""The percentiles' intervals (``ffrf.studies.statistics``): they cover the population's percentile as often as
they claim."""

import numpy as np
import pytest
from scipy.stats import expon

from ffrf.studies.statistics import percentile_interval


@pytest.mark.parametrize("n, level", [(200, 50.0), (2000, 95.0), (2000, 99.0), (50, 5.0)])
def test_the_interval_covers_the_true_percentile_at_least_95_percent_of_the_time(n, level):
    """2000 samples of n from the exponential distribution (skewed, as a largest deviation is): the interval of the
    level-th percentile holds the exact one, -ln(1 - p), in at least 94 % of them (95 % nominal; the order
    statistics' interval is conservative, and 2000 repetitions estimate a 95 % rate to +-1 %). With 50 values the
    5th percentile has no lower bound at that confidence (0.95^50 = 0.077 > 0.025 of samples lie all above it)."""
    rng = np.random.default_rng(int(level * 10) + n)
    exact = expon.ppf(level / 100.0)
    hits = 0
    for _ in range(2000):
        low, high = percentile_interval(np.sort(rng.exponential(size=n)), level)
        hits += low <= exact <= high
    assert hits / 2000 >= 0.94, hits / 2000


def test_an_end_a_small_sample_cannot_bound_is_infinite():
    """Three values and the 99th percentile: all three lie below it with probability 0.99^3 = 0.97 > 0.025, so no
    order statistic bounds it from above with 95 % confidence; from below the second does (P(B <= 1) = 3e-4)."""
    assert percentile_interval(np.array([1.0, 2.0, 3.0]), 99.0) == (2.0, np.inf)
