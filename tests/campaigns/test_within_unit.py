"""Known answers of the within-unit detection statistics (campaigns.analysis.within_unit) on constructed units.

Every unit is ``offset_u + k * level + N(0, sigma)``: a fixed offset per unit (its fixed errors, drawn large), a
feature sensitivity ``k`` per metre of fault, and a Gaussian test-to-test noise. A unit's threshold is its baseline
mean plus the prediction bound ``t sigma sqrt(1 + 1/R)`` (R baseline repeats), so the growth it detects with power
0.95 is ``d_u = (threshold_u - offset_u + z_0.95 sigma) / k``, and over units ``d_u`` is normal around
``(z_0.95 sqrt(1 + 1/R) + z_0.95) sigma / k`` with standard deviation ``sigma / (k sqrt(R))`` (the unit's baseline
mean). The classical ``(z_(1-alpha) + z_power) sigma / k`` is the limit of many baseline repeats.

Tolerances come from the sample sizes: a unit's estimate rests on its mean at each level, off by ``sigma / sqrt(R)``
(``sigma / (k sqrt(R))`` in fault size), so 4 of those plus one sweep step (the interpolation between levels) bound
every unit's error except with probability about 59 x 6e-5. Coverage counts are binomial, as in
test_small_sample_statistics: K seeds of N covering with probability p lie below the 0.1 % quantile of Binomial(N, p)
once in a thousand seed lists; the seeds are fixed, so the outcome never changes from one run to the next.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from campaigns.analysis.vocabulary import BACKLASH_REQUIREMENT
from campaigns.analysis.within_unit import _first_detected, population_detectable, unit_detection, within_unit_dataset
from campaigns.statistics.detection import RESOLUTIONS, bootstrap_minimum_detectable, minimum_detectable
from campaigns.statistics.order_statistics import min_runs_for_quantile_bound
from campaigns.statistics.within_unit_floors import DESIGN_REVIEW_QUANTILE, MIN_REPEATS, MIN_UNITS, unit_floor

#: Test-to-test noise of the feature [V] and its sensitivity to the fault [V/m]: sigma / k = 1 µm of backlash.
SIGMA, K = 0.01, 1e4
#: Fixed offsets of the units: 100 sigma, so the units' baselines do not overlap.
OFFSET_SCATTER = 100 * SIGMA
REPEATS = 10
#: Sweep step: half of sigma / k, so the detectable growth (about 3.4 sigma / k) lies inside an 11-level sweep.
STEP = 0.5 * SIGMA / K
LEVELS = np.arange(11) * STEP
Z = stats.norm.ppf(0.95)
#: Seeds of the coverage test.
COVERAGE_SEEDS = range(20)


def units(seed, n_units=MIN_UNITS, repeats=REPEATS, levels=LEVELS, sensitivity=K, sigma=SIGMA):
    """``values[level, unit, repeat]`` of constructed units, and their offsets."""
    rng = np.random.default_rng(seed)
    offsets = rng.normal(0.0, OFFSET_SCATTER, n_units)
    noise = rng.normal(0.0, 1.0, (len(levels), n_units, repeats)) * np.broadcast_to(sigma, n_units)[:, None]
    return offsets[None, :, None] + sensitivity * levels[:, None, None] + noise, offsets


def quantile_truth(q, repeats=REPEATS):
    """The ``q`` quantile over units of the growth a unit detects with power 0.95 (module docstring)."""
    return (Z * math.sqrt(1 + 1 / repeats) + stats.norm.ppf(q) / math.sqrt(repeats) + Z) * SIGMA / K


# --- floors -------------------------------------------------------------------------------------------------------


def test_the_floors_are_the_order_statistics_of_the_units_and_the_check_of_the_scatter():
    """59 units: the largest of them bounds the 95th-percentile unit at 95 %; the median alone would need 5."""
    assert MIN_UNITS == unit_floor() == min_runs_for_quantile_bound(0.95, 0.95) == 59
    assert unit_floor((0.5,)) == 5
    assert MIN_REPEATS == 3
    with pytest.raises(ValueError, match="min_repeats = 2: must be at least 3"):
        unit_detection(LEVELS, units(0)[0], min_repeats=2)


# --- (a) known answers --------------------------------------------------------------------------------------------


def test_each_units_threshold_and_detectable_growth_are_the_analytic_ones():
    values, offsets = units(0)
    found = unit_detection(LEVELS, values)
    baseline = values[0]
    dof = MIN_UNITS * (REPEATS - 1)
    pooled = math.sqrt(((baseline - baseline.mean(axis=1, keepdims=True)) ** 2).sum() / dof)
    assert found["dof"][0] == dof and found["scatter"][0] == pytest.approx(pooled)
    margin = stats.t.ppf(0.95, dof) * pooled * math.sqrt(1 + 1 / REPEATS)
    np.testing.assert_allclose(found["threshold_high"], baseline.mean(axis=1) + margin)
    np.testing.assert_allclose(found["threshold_low"], baseline.mean(axis=1) - margin)
    # a test at a level is flagged as often as a normal test of the level's mean and pooled scatter exceeds it
    level = 6
    expected = stats.norm.sf((found["threshold_high"] - values[level].mean(axis=1)) / found["scatter"][level])
    np.testing.assert_allclose(found["probability"][level], expected)
    truth = (found["threshold_high"] - offsets + Z * SIGMA) / K
    tolerance = 4 * SIGMA / (K * math.sqrt(REPEATS)) + STEP
    assert np.abs(found["estimate"] - truth).max() < tolerance
    median_se = math.sqrt(math.pi / 2) * SIGMA / (K * math.sqrt(REPEATS * MIN_UNITS))
    assert np.median(found["estimate"]) == pytest.approx(quantile_truth(0.5), abs=4 * median_se + STEP)
    # the classical limit is below it by the prediction bound's extra sqrt(1 + 1/R)
    assert quantile_truth(0.5) > 2 * Z * SIGMA / K
    for u in range(MIN_UNITS):
        assert tuple(found["bracket"][u]) == minimum_detectable(LEVELS, found["probability"][:, u])[1:]


def test_the_units_thresholds_flag_the_false_alarm_rate_of_fresh_baseline_tests():
    """The prediction bound keeps the false-alarm rate at 5 % over units with 10 baseline repeats each (within 4
    standard errors of the mean rate over units: each unit's rate varies with its baseline mean). The unit's own
    empirical 95 % quantile of its repeats lies between its two largest, whose expected tails are 2/11 and 1/11
    (E[1 - F(X_(r))] = (n + 1 - r) / (n + 1)): it flags more than 1/11, the sample maximum's."""
    values, offsets = units(8)
    found = unit_detection(LEVELS, values)
    fresh = offsets[:, None] + np.random.default_rng(9).normal(0.0, SIGMA, (MIN_UNITS, 2000))
    rates = (fresh > found["threshold_high"][:, None]).mean(axis=1)
    assert rates.mean() == pytest.approx(0.05, abs=4 * rates.std() / math.sqrt(MIN_UNITS))
    empirical = np.quantile(values[0], 0.95, axis=1)
    assert (fresh > empirical[:, None]).mean() > 1 / 11


def test_a_feature_falling_with_the_fault_is_detected_on_the_low_side_alike():
    values, _ = units(1)
    rising, falling = unit_detection(LEVELS, values), unit_detection(LEVELS, -values)
    np.testing.assert_allclose(falling["probability"], rising["probability"])
    np.testing.assert_allclose(falling["threshold_low"], -rising["threshold_high"])


def test_the_bounds_of_the_median_and_design_review_units_cover_their_quantiles():
    """Bounds are sweep levels around the truth (strictly: a level equal to it would be neither side)."""
    covered = {q: 0 for q in (0.5, DESIGN_REVIEW_QUANTILE)}
    for seed in COVERAGE_SEEDS:
        found = population_detectable(LEVELS, units(seed)[0], n_boot=200, seed=seed)
        for i, q in enumerate(found["quantiles"]):
            lower, upper = found["bounds"][i]
            assert lower <= found["bracket"][i][0] and found["bracket"][i][1] <= upper
            covered[q] += lower < quantile_truth(q) < upper
    # nominal coverage 0.95 at least (the bounds are sweep levels widened to the order statistics)
    floor = stats.binom.ppf(0.001, len(COVERAGE_SEEDS), 0.95)
    assert min(covered.values()) >= floor


def test_the_vectorised_bracket_is_that_of_minimum_detectable():
    rng = np.random.default_rng(2)
    probability = np.sort(rng.uniform(0.0, 1.0, (len(LEVELS), 200)), axis=0)
    probability[:, :20] *= 0.9  # some units never reach the power
    probability[0, 20:25] = 0.97  # and some are detected at the baseline
    lower, upper = _first_detected(LEVELS, probability, 0.95)
    for u in range(probability.shape[1]):
        assert (lower[u], upper[u]) == minimum_detectable(LEVELS, probability[:, u])[1:]


# --- (b) between-unit against within-unit -------------------------------------------------------------------------


def test_offsets_far_above_the_noise_hide_the_fault_between_units_but_not_within():
    """Offsets of 100 sigma: the pooled population's thresholds lie among the offsets, so between units only a fault
    of the order of the offsets' spread (100 sigma / k = 100 µm) is detected; within units, about 3.4 µm."""
    levels = np.concatenate([LEVELS, [1e-5, 1e-4, 1e-3]])
    values, _ = units(3, levels=levels)
    within = population_detectable(levels, values, n_boot=200, seed=3)
    between = bootstrap_minimum_detectable(levels, list(values.reshape(len(levels), -1)), 0, n_boot=200, seed=3)
    design_review = within["bounds"][list(within["quantiles"]).index(DESIGN_REVIEW_QUANTILE)]
    assert design_review[1] <= LEVELS[-1]
    assert between["bounds"][0] >= 1e-4 > 20 * design_review[1]


# --- (c) below the floors -----------------------------------------------------------------------------------------


@pytest.mark.parametrize(("n_units", "repeats", "used"), [(MIN_UNITS - 1, REPEATS, MIN_UNITS - 1), (80, 2, 0)])
def test_fewer_units_or_repeats_than_the_floor_give_insufficient_data(n_units, repeats, used):
    values, _ = units(4, n_units=n_units, repeats=repeats)
    ds = within_unit_dataset(LEVELS, values, n_boot=50, seed=4)
    assert ds["within_unit_requirement_verdict"].item() == "insufficient data"
    assert int(ds["within_unit_n_units_used"]) == used
    assert (ds["within_unit_minimum_detectable_status"] == RESOLUTIONS.index("insufficient_data")).all()
    assert ds["within_unit_minimum_detectable_backlash_ci"].isnull().all()
    statement = ds["within_unit_requirement_statement"].item()
    assert statement.startswith(f"insufficient data: {used} of {n_units} units have at least 3 ok repeats at every "
                                f"level; at least {MIN_UNITS} are needed")
    assert statement.endswith("against the 1 µm requirement of Table 9.3")


# --- (d) failed runs ----------------------------------------------------------------------------------------------


def test_failed_runs_are_excluded_counted_and_a_unit_left_short_is_not_used():
    values, _ = units(5, n_units=MIN_UNITS + 1)
    values[0, 0, :4] = np.nan  # 6 repeats left: used
    values[3, 1, 1] = np.inf
    values[5, 2, 2:] = np.nan  # 2 repeats left: unit 2 is not used
    found = unit_detection(LEVELS, values)
    assert found["n_excluded"].sum() == 4 + 1 + 8
    assert found["n_excluded"][0, 0] == 4 and found["n_used"][0, 0] == 6 and found["n_used"][3, 1] == 9
    assert found["used"].sum() == MIN_UNITS and not found["used"][2]
    assert np.isnan(found["probability"][:, 2]).all() and np.isnan(found["bracket"][2]).all()
    kept = np.delete(values, 2, axis=1)
    baseline = [row[np.isfinite(row)] for row in kept[0]]
    dof = sum(len(b) - 1 for b in baseline)
    pooled = math.sqrt(sum(((b - b.mean()) ** 2).sum() for b in baseline) / dof)
    assert found["dof"][0] == dof == MIN_UNITS * (REPEATS - 1) - 4
    margin = stats.t.ppf(0.95, dof) * pooled * math.sqrt(1 + 1 / 6)
    assert found["threshold_high"][0] == pytest.approx(baseline[0].mean() + margin)
    ds = within_unit_dataset(LEVELS, values, n_boot=50, seed=5)
    assert int(ds["within_unit_n_units_used"]) == MIN_UNITS
    assert ds["within_unit_requirement_verdict"].item() != "insufficient data"
    assert "6–10 ok repeats per unit and level" in ds["within_unit_requirement_statement"].item()


# --- (e) bad inputs -----------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("levels", "shape", "message"), [
    ([0.0], (1, 3, 4), r"levels has shape \(1,\): must be one-dimensional with at least 2 fault sizes"),
    ([[0.0, 1e-6]], (2, 3, 4), r"levels has shape \(1, 2\): must be one-dimensional"),
    ([0.0, 2e-6, 1e-6], (3, 3, 4), r"levels = .*: must be finite and strictly increasing from 0"),
    ([0.0, 1e-6, 1e-6], (3, 3, 4), r"levels = .*: must be finite and strictly increasing from 0"),
    ([1e-6, 2e-6], (2, 3, 4), r"levels = .*: must be finite and strictly increasing from 0"),
    ([0.0, math.nan], (2, 3, 4), r"levels = .*: must be finite"),
    (["0", "a"], (2, 3, 4), r"levels: must be numbers"),
    ([0.0, 1e-6], (2, 12), r"values has shape \(2, 12\): must be \(level, unit, repeat\) = \(2, U, R\)"),
    ([0.0, 1e-6], (3, 3, 4), r"values has shape \(3, 3, 4\): must be \(level, unit, repeat\) = \(2, U, R\)"),
    ([0.0, 1e-6], (2, 0, 4), r"values has shape \(2, 0, 4\): .* U >= 1 units and R >= 1 repeats"),
])
def test_bad_inputs_raise_one_value_error_naming_the_argument(levels, shape, message):
    for function in (unit_detection, population_detectable, within_unit_dataset):
        with pytest.raises(ValueError, match=message):
            function(levels, np.zeros(shape))


def test_the_quantiles_must_include_the_design_review_unit():
    with pytest.raises(ValueError, match=r"quantiles = \(0.5,\): must .* include the design-review quantile 0.95"):
        population_detectable(LEVELS, units(0)[0], quantiles=(0.5,))


# --- the dataset and its sentence ---------------------------------------------------------------------------------


def test_the_dataset_states_units_and_the_sentence_prints_only_resolved_values():
    values, _ = units(6)
    ds = within_unit_dataset(LEVELS, values, feature_units="V", n_boot=200, seed=6)
    for name, variable in ds.data_vars.items():
        if variable.dtype.kind in "fiu":
            assert "units" in variable.attrs or "flag_values" in variable.attrs, name
        assert variable.attrs.get("long_name"), name
    assert ds["within_unit_scatter"].attrs["units"] == "V"
    assert ds["within_unit_minimum_detectable_backlash_ci"].attrs["units"] == "m"
    statement = ds["within_unit_requirement_statement"].item()
    verdict = ds["within_unit_requirement_verdict"].item()
    # sigma / k = 1 µm: about 3.4 µm is detected, so the 1 µm requirement is not met
    assert verdict == "not met" and statement.startswith("not met: within-unit minimum detectable backlash growth")
    for q, name in ((DESIGN_REVIEW_QUANTILE, "95th-percentile unit"), (0.5, "median unit")):
        row = ds.sel(unit_quantile=q)
        status = RESOLUTIONS[int(row["within_unit_minimum_detectable_status"])]
        lower, upper = row["within_unit_minimum_detectable_bracket"].values * 1e6
        if status == "resolved":
            assert np.isfinite(row["within_unit_minimum_detectable_backlash"])
        else:
            assert np.isnan(row["within_unit_minimum_detectable_backlash"])
            assert f"{name} between the adjacent sweep levels {lower:.3g} µm and {upper:.3g} µm" in statement
    assert f"bounds over {MIN_UNITS} units, 10 ok repeats per unit and level, 11 levels" in statement
    assert "the shared test-to-test distribution is not rejected" in statement
    met = within_unit_dataset(LEVELS, values, n_boot=200, seed=6, requirement=LEVELS[-1])
    assert met["within_unit_requirement_verdict"].item() == "met"
    assert met["within_unit_requirement_statement"].item().endswith(
        f"smallest p = {np.nanmin(ds['within_unit_equal_scatter_pvalue']):.2g} and "
        f"{np.nanmin(ds['within_unit_normality_pvalue']):.2g}, at 0.05 over 11 levels)")
    assert BACKLASH_REQUIREMENT == ds["within_unit_minimum_detectable_backlash"].attrs["requirement"]


def test_units_that_scatter_differently_are_reported_as_rejecting_the_shared_distribution():
    sigma = np.where(np.arange(MIN_UNITS) % 2 == 0, SIGMA, 4 * SIGMA)
    values, _ = units(7, sigma=sigma)
    ds = within_unit_dataset(LEVELS, values, n_boot=50, seed=7)
    assert (ds["within_unit_equal_scatter_pvalue"] < 0.05 / len(LEVELS)).all()
    assert "the shared test-to-test distribution is rejected at level 0 µm" in (
        ds["within_unit_requirement_statement"].item())
