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


def test_the_yields_interval_is_clopper_pearsons():
    """No print of 100 beyond the limit: the fraction's exact 95 % interval is [0, 1 - 0.025^(1/100)] (the closed form
    of Clopper and Pearson at k = 0), the yield's [0.025^(1/100), 1]; NaN rows (failed prints) are not counted."""
    from ffrf.studies.statistics import exceedance

    values = np.concatenate([np.linspace(0.1, 0.9, 100), [np.nan, np.nan]])
    result = exceedance(values, 1.0)
    assert result["n"] == 100 and result["exceeding"] == 0 and result["yield"] == 1.0
    assert result["fraction_high"] == pytest.approx(1.0 - 0.025 ** (1 / 100), rel=1e-9)
    assert result["yield_low"] == pytest.approx(0.025 ** (1 / 100), rel=1e-9)
    half = exceedance(np.arange(100.0), 49.5)  # 50 of 100 above
    assert half["fraction"] == 0.5 and half["fraction_low"] < 0.5 < half["fraction_high"]


def test_a_limit_on_an_output_the_study_does_not_have_is_refused():
    from ffrf.errors import SceneError
    from ffrf.paper.bennett_scene import STUDY_BASES
    from ffrf.studies.spec import study_from_document

    document = {
        "study": {"name": "limits", "method": "grid"},
        "base": {"bennett": "pla"},
        "parameters": [{"name": "twist", "target": "bore_twist_deg", "joint": 3, "link": 0, "values": [0.0]}],
        "limits": [{"output": "max_coupler_deviation_mm", "above": 1.0}],
    }
    with pytest.raises(SceneError, match="'max_coupler_deviation_mm' is not one of this study's"):
        study_from_document(document, bases=STUDY_BASES)
