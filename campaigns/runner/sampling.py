"""Sampling of the uncertainty table: stateless, per-run random streams.

Run ``i`` of data set ``d`` (both zero-based, in spec order) owns the seed
sequence ``SeedSequence(root_seed, spawn_key=(d, i))``, unless the data set takes
the seeds of another (``seeds_from``: then ``d`` is that data set's index, and
run ``i`` of both draws the same values and the same noise). Its two children
(``.spawn(2)``) feed

* child 0: the uncertain values, drawn in the order of the uncertainty table;
* child 1: the run's sensor-noise :class:`numpy.random.Generator`.

A within-unit campaign (the spec's ``[units]``: run ``i`` tests unit ``u = i // repeats``) draws the unit's fixed
errors from a stream of the unit alone, ``SeedSequence(root_seed, spawn_key=(UNIT_STREAM, u))``, the same in every
data set: each row that is not redrawn from test to test takes its value from that stream (the whole table is drawn
from it in table order, so moving a row between per-test and per-unit changes that row only), and the per-test rows
and the noise come from the run's own ``(d, i)`` streams as above. The unit's tests at every fault level therefore
share its fixed errors (common random numbers across the unit's tests).

No state is carried from run to run, so any run can be replayed alone
(:func:`sample_run` and :func:`noise_generator` with its indices), and the
values do not depend on how runs are grouped into chunks or spread over workers.
Sampling happens in the driver before anything is submitted (the samples are
stored next to the results); analysis is a separate module.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from scipy import special

from campaigns.runner.distributions import Distribution

#: Index of each child of a run's seed sequence.
PARAMETER_STREAM, NOISE_STREAM = 0, 1
#: First spawn key of a unit's stream: no data set index reaches it (a spec holds a few dozen data sets), so a unit's
#: stream ``(UNIT_STREAM, u)`` is never a run's ``(d, i)``.
UNIT_STREAM = 2**31 - 1


def run_seed_sequence(root_seed: int, dataset_index: int, run_index: int) -> np.random.SeedSequence:
    """The seed sequence of one run (see the module docstring)."""
    return np.random.SeedSequence(root_seed, spawn_key=(dataset_index, run_index))


def _stream(root_seed: int, dataset_index: int, run_index: int, which: int) -> np.random.Generator:
    return np.random.default_rng(run_seed_sequence(root_seed, dataset_index, run_index).spawn(2)[which])


def noise_generator(root_seed: int, dataset_index: int, run_index: int) -> np.random.Generator:
    """The sensor-noise generator of one run (child 1 of its seed sequence)."""
    return _stream(root_seed, dataset_index, run_index, NOISE_STREAM)


def unit_generator(root_seed: int, unit: int) -> np.random.Generator:
    """The generator of unit ``unit``'s fixed errors in a within-unit campaign (see the module docstring)."""
    return np.random.default_rng(np.random.SeedSequence(root_seed, spawn_key=(UNIT_STREAM, unit)))


def draw(distribution: Distribution, rng: np.random.Generator) -> float:
    """Draw one value of ``distribution`` (SI units) from ``rng``."""
    d = distribution
    if d.kind == "constant":
        return d.value
    if d.kind == "uniform":
        return float(rng.uniform(d.low, d.high))
    if d.kind == "gaussian":
        return float(rng.normal(d.mean, d.sigma))
    if d.kind == "lognormal":
        return d.mean * math.exp(float(rng.normal(0.0, d.sigma)))  # libm, not numpy's CPU-dispatched exp
    if d.kind == "truncated_gaussian":
        if d.sigma == 0.0:
            return d.mean
        return _truncated_normal(d.mean, d.sigma, d.low, d.high, rng)
    raise ValueError(f"unknown distribution kind {d.kind!r}")


def _truncated_normal(mean: float, sigma: float, low: float, high: float, rng: np.random.Generator) -> float:
    """Inverse-CDF draw of N(mean, sigma) truncated to [low, high].

    Exact, one uniform per draw, and ~100x faster per scalar than
    ``scipy.stats.truncnorm.rvs``. Bounds entirely above the mean are mirrored
    below it, where the normal CDF keeps its relative precision.
    """
    a, b = (low - mean) / sigma, (high - mean) / sigma
    sign = 1.0
    if a > 0.0:
        a, b, sign = -b, -a, -1.0
    u = rng.uniform(special.ndtr(a), special.ndtr(b))
    return float(mean + sign * sigma * np.clip(special.ndtri(u), a, b))


def sample_run(distributions: Sequence[Distribution], root_seed: int, seed_index: int, run_index: int,
               fixed: Mapping[int, float] | None = None, *, unit: int | None = None,
               per_unit: Sequence[int] = ()) -> np.ndarray:
    """The uncertain values of one run, in table order (replays that run alone).

    ``seed_index`` is the data set whose streams the run uses (its own index unless the data set takes another's
    seeds: ``CampaignSpec.seed_index``). ``fixed`` maps table columns to the values a data set fixes them at
    (``CampaignSpec.fixed_columns``): every value is drawn first, so fixing one leaves the others as they were.
    In a within-unit campaign ``unit`` is the unit the run tests and ``per_unit`` the columns drawn from that unit's
    stream (``CampaignSpec.unit_draws``); the fixed values still win.
    """
    rng = _stream(root_seed, seed_index, run_index, PARAMETER_STREAM)
    values = np.array([draw(d, rng) for d in distributions], dtype=float)
    if unit is not None:
        unit_rng = unit_generator(root_seed, unit)
        unit_values = np.array([draw(d, unit_rng) for d in distributions], dtype=float)
        values[list(per_unit)] = unit_values[list(per_unit)]
    for column, value in (fixed or {}).items():
        values[column] = value
    return values


def sample(spec) -> np.ndarray:
    """All sampled values of a campaign.

    Parameters
    ----------
    spec : campaigns.runner.spec.CampaignSpec
        The validated spec (its resolved distributions, data sets, runs and root seed).

    Returns
    -------
    numpy.ndarray
        Shape ``(n_datasets, runs_per_dataset, n_uncertainties)``, SI units.
    """
    distributions = spec.distributions()
    targets = [d.target for d in distributions]
    out = np.empty((len(spec.datasets), spec.runs_per_dataset, len(distributions)))
    for d in range(len(spec.datasets)):
        seed_index, fixed = spec.seed_index(d), spec.fixed_columns(d, targets)
        for i in range(spec.runs_per_dataset):
            out[d, i] = sample_run(distributions, spec.root_seed, seed_index, i, fixed, **spec.unit_draws(i, targets))
    return out
