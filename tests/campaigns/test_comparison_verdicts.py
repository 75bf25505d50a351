"""Known answers of campaigns.statistics.paired_comparison's verdict vocabulary (the worst of several verdicts) and of
the spread of an ensemble of tight runs. The verdicts themselves are the accuracy rule's:
tests/campaigns/test_accuracy_rule.py."""

import math

import numpy as np
import pytest
from scipy import stats

from campaigns.statistics.paired_comparison import ensemble_spread, worst_verdict


@pytest.mark.parametrize(("verdicts", "worst"), [
    (["met", "met"], "met"),
    (["met", "undetermined", "insufficient data"], "undetermined"),
    (["met", "insufficient data"], "insufficient data"),
    (["undetermined", "not met", "met"], "not met"),
    ([], "insufficient data"),
])
def test_worst_verdict(verdicts, worst):
    assert worst_verdict(verdicts) == worst


def test_ensemble_spread_chi_square_interval_covers_the_true_sigma():
    """Known answer: 10 members, interval sigma * sqrt(9 / chi2 quantiles); over many normal ensembles the 95 %
    interval holds the true sigma in 95 % of them (binomial 3-sigma band for 2000 trials: 0.935-0.965)."""
    spread = ensemble_spread([1.0, 2.0, 3.0, 4.0, math.nan])
    assert spread["n"] == 4 and spread["range"] == 3.0 and spread["std"] == pytest.approx(np.std([1, 2, 3, 4], ddof=1))
    assert spread["std_upper"] == pytest.approx(spread["std"] * math.sqrt(3 / stats.chi2.ppf(0.025, 3)))
    rng = np.random.default_rng(11)
    covered = [s["std_lower"] <= 0.1 <= s["std_upper"]
               for s in (ensemble_spread(rng.normal(0, 0.1, 10)) for _ in range(2000))]
    assert 0.935 <= np.mean(covered) <= 0.965
    assert math.isnan(ensemble_spread([1.0])["std"])
