"""Known answers of the two verdicts of campaigns.comparison: a candidate against a reference ensemble, and a paired
mean shift against a tolerance and a numerical floor."""

import math

import numpy as np
import pytest
from scipy import stats

from campaigns.comparison import ensemble_spread, paired_shift_verdict, reference_verdict, worst_verdict

UM = 1e-6
TARGET = 0.1 * UM


@pytest.mark.parametrize(("candidate", "references", "verdict", "lower", "upper"), [
    # references 30.00-30.02 um: centre 30.01, half-width 0.01
    (30.05 * UM, [30.00 * UM, 30.02 * UM, 30.01 * UM], "met", 0.03 * UM, 0.05 * UM),
    (30.25 * UM, [30.00 * UM, 30.02 * UM, 30.01 * UM], "not met", 0.23 * UM, 0.25 * UM),
    # the references disagree by more than the target: nearest 0.02, farthest 0.16 um
    (30.16 * UM, [30.00 * UM, 30.14 * UM], "undetermined", 0.02 * UM, 0.16 * UM),
    # inside the references' range: the lower bound is 0
    (30.07 * UM, [29.95 * UM, 30.14 * UM], "undetermined", 0.0, 0.12 * UM),
    # exactly on the target: met (the target is inclusive)
    (TARGET, [0.0], "met", TARGET, TARGET),
])
def test_reference_verdict_known_answers(candidate, references, verdict, lower, upper):
    found = reference_verdict(candidate, references, TARGET)
    assert found.verdict == verdict
    assert found.lower == pytest.approx(lower, abs=1e-15) and found.upper == pytest.approx(upper, abs=1e-15)
    assert found.n == len(references)
    assert found.statement.startswith(f"{verdict}: ") and f"of {len(references)} references" in found.statement


def test_reference_verdict_bounds_are_the_nearest_and_farthest_reference():
    refs = np.random.default_rng(1).normal(30e-6, 0.05e-6, 9)
    found = reference_verdict(30.2e-6, refs, TARGET)
    assert found.lower == pytest.approx(np.abs(30.2e-6 - refs).min(), abs=1e-18)
    assert found.upper == pytest.approx(np.abs(30.2e-6 - refs).max(), abs=1e-18)


def test_reference_verdict_without_data_is_insufficient():
    assert reference_verdict(1e-6, [math.nan, math.nan], TARGET).verdict == "insufficient data"
    found = reference_verdict(math.nan, [1e-6], TARGET)
    assert found.verdict == "insufficient data" and "candidate" in found.statement and found.n == 1


def _shifts(mean, sd, n, seed=0):
    """n paired differences with exactly the given sample mean and standard deviation."""
    z = np.random.default_rng(seed).normal(size=n)
    return mean + sd * (z - z.mean()) / z.std(ddof=1)


def test_paired_shift_interval_is_students_t():
    d = _shifts(0.03 * UM, 0.05 * UM, 10)
    found = paired_shift_verdict(d, TARGET)
    half = stats.t.ppf(0.975, 9) * 0.05 * UM / math.sqrt(10)
    assert found.estimate == pytest.approx(0.03 * UM) and found.n == 10
    assert (found.lower, found.upper) == pytest.approx((0.03 * UM - half, 0.03 * UM + half))


@pytest.mark.parametrize(("mean", "sd", "n", "floor", "verdict"), [
    (0.01 * UM, 0.02 * UM, 20, 0.0, "met"),               # clearly inside: interval about ±0.02 around 0.01
    (-0.3 * UM, 0.05 * UM, 20, 0.0, "not met"),           # clearly outside
    (0.1 * UM, 0.2 * UM, 10, 0.0, "undetermined"),        # straddles the tolerance
    (0.25 * UM, 0.05 * UM, 20, 0.2 * UM, "undetermined"),  # beyond the tolerance, not beyond tolerance + floor
    (0.25 * UM, 0.05 * UM, 20, 0.1 * UM, "not met"),      # beyond tolerance + floor (interval 0.227-0.273 um)
])
def test_paired_shift_known_answers(mean, sd, n, floor, verdict):
    found = paired_shift_verdict(_shifts(mean, sd, n), TARGET, floor)
    assert found.verdict == verdict
    assert found.statement.startswith(f"{verdict}: mean shift {mean * 1e6:+.4f} µm") and f"n = {n}" in found.statement
    assert ("numerical floor not measured" in found.statement) == (floor == 0)


@pytest.mark.parametrize("differences", [[], [0.01 * UM], [0.01 * UM, math.nan, math.inf]])
def test_paired_shift_with_too_few_pairs_is_insufficient_data(differences):
    found = paired_shift_verdict(differences, TARGET)
    assert found.verdict == "insufficient data" and found.n == len([d for d in differences if math.isfinite(d)])
    assert "at least 2 needed" in found.statement and math.isnan(found.lower)


def test_identical_runs_meet_the_tolerance():
    """auto bit-identical to full on every run: a zero-width interval at 0."""
    assert paired_shift_verdict(np.zeros(5), TARGET).verdict == "met"


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
