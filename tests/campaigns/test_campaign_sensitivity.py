"""Given-data first-order indices and effect sizes on functions whose indices are known.

Tolerances come from the estimator's spread: over 20 seeds of n = 1000 runs the first-order index of the
Ishigami and linear test functions scatters with a standard deviation of about 0.02 (and about 0.003 for the
V-shaped function, whose index is close to 1); it shrinks as 1/sqrt(n).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from campaign_helpers import SYNTHETIC_SPEC, load
from SALib.analyze import rbd_fast
from scipy import stats

from campaigns.runner.execution import build_request
from campaigns.runner.runs import execute
from campaigns.runner.sampling import sample
from campaigns.runner.synthetic import NOISE_SIGMA, TEMPERATURE_SLOPE, synthetic_run
from campaigns.statistics.correlation import prcc
from campaigns.statistics.sensitivity import _easi_order, _first_order_of_signals, first_order


def ishigami(X, a=7.0, b=0.1):
    return np.sin(X[:, 0]) + a * np.sin(X[:, 1]) ** 2 + b * X[:, 2] ** 4 * np.sin(X[:, 0])


def ishigami_first_order(a=7.0, b=0.1):
    """Closed form (Ishigami & Homma 1990; Sobol' & Levitan 1999) for inputs uniform on [-pi, pi]."""
    v1 = 0.5 * (1 + b * math.pi**4 / 5) ** 2
    v2 = a**2 / 8
    variance = v1 + v2 + b**2 * math.pi**8 * 8 / 225
    return np.array([v1, v2, 0.0]) / variance


def test_ishigami_closed_form():
    np.testing.assert_allclose(ishigami_first_order(), [0.3139, 0.4424, 0.0], atol=1e-4)


def test_ishigami_indices_are_recovered():
    """n = 4000: estimator spread about 0.01, so 0.04 is four of them."""
    rng = np.random.default_rng(11)
    X = rng.uniform(-math.pi, math.pi, (4000, 3))
    found = first_order(X, ishigami(X), seed=1)
    np.testing.assert_allclose(found["index"], ishigami_first_order(), atol=0.04)
    assert (found["ci"][:, 0] <= found["index"]).all() and (found["index"] <= found["ci"][:, 1]).all()
    assert found["ci"][2, 0] < 0.02  # x3 acts only through its interaction with x1: no first-order effect


def test_the_point_estimate_is_salibs():
    rng = np.random.default_rng(12)
    X = rng.uniform(-math.pi, math.pi, (1000, 3))
    y = ishigami(X)
    expected = rbd_fast.analyze({"num_vars": 3, "names": ["x1", "x2", "x3"]}, X, y, seed=0)["S1"]
    np.testing.assert_allclose(first_order(X, y, n_boot=10, seed=0)["index"], expected, rtol=1e-12)
    # the batched estimator of the bootstrap, applied to the sample itself, is the same estimator
    signal = y[np.argsort(X[:, 0])][_easi_order(1000)]
    assert _first_order_of_signals(signal[None, :])[0] == pytest.approx(expected[0], rel=1e-12)


def test_a_v_shaped_dependence_is_found_where_prcc_sees_nothing():
    """y = |x1| + N(0, 0.05), x ~ U(-1, 1): E[y | x1] = |x1|, whose variance is 1/3 - 1/4 = 1/12."""
    rng = np.random.default_rng(13)
    X = rng.uniform(-1.0, 1.0, (1000, 2))
    y = np.abs(X[:, 0]) + rng.normal(0.0, 0.05, 1000)
    assert np.abs(prcc(X, y)).max() < 0.1  # sampling spread of a zero rank correlation is 1/sqrt(n) = 0.03
    found = first_order(X, y, seed=2)
    truth = (1 / 12) / (1 / 12 + 0.05**2)
    assert found["index"][0] == pytest.approx(truth, abs=0.01) and found["ci"][0, 0] > 0.9
    assert found["effect_size"][0] == pytest.approx(math.sqrt(1 / 12), rel=0.02)
    assert found["ci"][1, 0] < 0.0 < found["ci"][1, 1]  # the inert parameter: zero inside its interval
    assert found["effect_size"][1] < 0.05


def test_an_additive_linear_function_has_the_squared_correlation_as_index():
    """Truncated Gaussian inputs (like Table 9.5): for y = 2 x1 + x2 + e, S1_j = corr(x_j, y)^2; n = 2000."""
    rng = np.random.default_rng(14)
    X = stats.truncnorm.rvs(-3, 3, size=(2000, 3), random_state=rng)
    y = X @ np.array([2.0, 1.0, 0.0]) + rng.normal(0.0, 1.0, 2000)
    found = first_order(X, y, seed=3)
    squared = np.array([stats.pearsonr(X[:, j], y)[0] ** 2 for j in range(3)])
    np.testing.assert_allclose(found["index"], squared, atol=0.04)
    # effect size of a linear term b x: |b| std(x)
    np.testing.assert_allclose(found["effect_size"][:2], [2.0 * X[:, 0].std(), X[:, 1].std()], rtol=0.05)


def test_effect_sizes_of_the_synthetic_model_bracket_its_known_spreads():
    """The synthetic model (campaigns.runner.synthetic), 1000 runs of data set 2 (80 um, no load): gain moves the
    feature by 80 um x std(gain) (2.7 um), the offset by std(offset) (0.58 um), the temperature by its slope
    x std(T) (0.29 um); the stiffness, inert and pressure rows do nothing there.

    The index's absolute resolution at n = 1000 is about 0.02, i.e. sqrt(0.02) x std(f) = 0.4 um of effect
    size here: the temperature's 0.29 um (index 0.011) is at that limit, so for it only the upper bound and
    its rank behind the gain are asserted (its interval's lower bound lands within a few per cent of the truth,
    on either side, depending on the sample)."""
    spec = load(SYNTHETIC_SPEC, runs=1000)
    drawn = sample(spec)
    samples, names = drawn[0], [d.target for d in spec.distributions()]
    y = np.array([execute(synthetic_run, build_request(spec, drawn, 0, i))["features"]["backlash_feature"]
                  for i in range(1000)])
    found = first_order(samples, y, seed=4)
    column = {n: j for j, n in enumerate(names)}

    def spread(name: str, slope: float = 1.0) -> float:
        return slope * samples[:, column[name]].std()

    for name, truth in (("synthetic.gain", spread("synthetic.gain", 80e-6)),
                        ("synthetic.offset", spread("synthetic.offset"))):
        lower, upper = found["effect_size_ci"][column[name]]
        assert lower <= truth <= upper, name
    assert found["effect_size"][column["synthetic.gain"]] == pytest.approx(spread("synthetic.gain", 80e-6), rel=0.05)
    temperature = column["scene.room_temperature"]
    assert spread("scene.room_temperature", TEMPERATURE_SLOPE) <= found["effect_size_ci"][temperature, 1]
    assert found["effect_size"][temperature] < 0.25 * found["effect_size"][column["synthetic.gain"]]
    for name in ("synthetic.inert", "scene.supply_pressure", "synthetic.stiffness"):
        assert found["effect_size_ci"][column[name], 0] <= NOISE_SIGMA, name


def test_degenerate_inputs_give_nan():
    rng = np.random.default_rng(15)
    X = rng.normal(size=(100, 2))
    X[:, 1] = 3.0
    found = first_order(X, X[:, 0], n_boot=20, seed=0)
    assert np.isfinite(found["index"][0]) and np.isnan(found["index"][1]) and np.isnan(found["ci"][1]).all()
    assert np.isnan(first_order(X, np.ones(100), n_boot=20)["index"]).all()  # constant feature
    assert np.isnan(first_order(X[:20], X[:20, 0], n_boot=20)["index"]).all()  # n <= 2 x 10 harmonics


def test_the_interval_is_deterministic_in_its_seed():
    rng = np.random.default_rng(16)
    X = rng.uniform(-math.pi, math.pi, (500, 3))
    y = ishigami(X)
    a, b, c = (first_order(X, y, n_boot=50, seed=s)["ci"] for s in (5, 5, 6))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
