"""Sampling: stateless per-run streams, distributions, noise stream."""

from __future__ import annotations

import numpy as np
import pytest
from campaign_helpers import SYNTHETIC_SPEC, load
from scipy import stats

from campaigns.runner.execution import build_request
from campaigns.runner.sampling import draw, noise_generator, run_seed_sequence, sample, sample_run
from campaigns.runner.spec import Distribution


def test_each_run_replays_alone():
    spec = load(SYNTHETIC_SPEC)
    samples = sample(spec)
    assert samples.shape == (4, 40, 6)
    np.testing.assert_array_equal(sample_run(spec.distributions(), spec.root_seed, 2, 17), samples[2, 17])
    # more runs or data sets do not change the runs that already existed
    np.testing.assert_array_equal(sample(load(SYNTHETIC_SPEC, runs=60))[:, :40], samples)


def test_runs_and_streams_are_distinct():
    spec = load(SYNTHETIC_SPEC)
    samples = sample(spec)
    assert len({tuple(row) for row in samples.reshape(-1, samples.shape[-1])}) == samples.shape[0] * samples.shape[1]
    # the noise generator is child 1 of the run's sequence, independent of the parameter stream (child 0)
    expected = np.random.default_rng(run_seed_sequence(spec.root_seed, 1, 5).spawn(2)[1]).normal(size=3)
    np.testing.assert_array_equal(noise_generator(spec.root_seed, 1, 5).normal(size=3), expected)
    request = build_request(spec, samples, 1, 5)
    np.testing.assert_array_equal(request.noise_rng().normal(size=3), expected)


def test_request_routes_scene_targets_to_conditions():
    spec = load(SYNTHETIC_SPEC)
    samples = sample(spec)
    request = build_request(spec, samples, 3, 0)
    assert request.conditions["preload"] == 1000.0
    assert request.conditions["room_temperature"] == samples[3, 0, 4]
    assert set(request.parameter_values) == {"synthetic.gain", "synthetic.offset", "synthetic.stiffness",
                                             "synthetic.inert"}
    assert request.trace_variables == ("nut1_position", "motor_current")
    assert build_request(spec, samples, 3, 2).trace_variables == ()


@pytest.mark.parametrize(
    "dist, mean, std, support",
    [
        (Distribution("x", "gaussian", "1", 1.0, mean=1.0, sigma=0.1), 1.0, 0.1, (-np.inf, np.inf)),
        (Distribution("x", "uniform", "1", 0.0, low=-1.0, high=3.0), 1.0, 4 / np.sqrt(12), (-1.0, 3.0)),
        (Distribution("x", "truncated_gaussian", "1", 0.0, mean=0.0, sigma=1.0, low=-1.0, high=1.0), 0.0,
         stats.truncnorm(-1, 1).std(), (-1.0, 1.0)),
        (Distribution("x", "lognormal", "1", 2.0, mean=2.0, sigma=0.1), 2.0 * np.exp(0.005),
         2.0 * np.sqrt((np.exp(0.01) - 1) * np.exp(0.01)), (0.0, np.inf)),
        (Distribution("x", "constant", "1", 0.0, value=4.0), 4.0, 0.0, (4.0, 4.0)),
    ],
)
def test_distribution_moments(dist, mean, std, support):
    """n = 4000 seeded draws: mean within 5 standard errors, std within 10 %."""
    rng = np.random.default_rng(7)
    x = np.array([draw(dist, rng) for _ in range(4000)])
    assert abs(x.mean() - mean) <= 5 * std / np.sqrt(len(x)) + 1e-12
    assert x.std() == pytest.approx(std, rel=0.1, abs=1e-12)
    assert support[0] <= x.min() and x.max() <= support[1]
