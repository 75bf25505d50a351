"""Issue 30, point 4: the runs that would decide an undetermined verdict, with known answers."""

from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr

from campaigns.analysis.campaign_analysis import analysis_dataset
from campaigns.analysis.margins import _fraction_bounds, _fraction_interval, fraction_runs_to_decide
from campaigns.statistics.detection import runs_to_decide

LEVELS = [0.0, 1e-6, 2e-6]


def test_the_detection_runs_follow_the_normal_scaling_of_the_bootstrap_error():
    """p = 0.97 at the 1 µm level with a bootstrap error of 2 points at 100 runs: 1.96 errors from 95 % at
    100 (1.96 * 0.02 / 0.02)^2 = 384.1 runs, so 385."""
    runs, reason = runs_to_decide(LEVELS, [0.05, 0.97, 1.0], [0.01, 0.02, 0.0], 100, 1e-6)
    assert runs == 385 and reason.startswith("met would be decided at about 385 ok runs per sweep data set")
    runs, reason = runs_to_decide(LEVELS, [0.05, 0.90, 1.0], [0.01, 0.03, 0.0], 100, 1e-6)
    assert runs == math.ceil(100 * (1.959963984540054 * 0.03 / 0.05) ** 2)
    assert reason.startswith("not met would be decided")


def test_a_level_the_normal_scaling_calls_decided_already_gets_no_number():
    """p = 0.267 with a bootstrap error of 27 points at 60 runs: 2.5 errors from 95 %, decided by the normal scaling,
    yet the verdict is undetermined (the percentile bounds decide): no number, the reason says why (it said "61")."""
    runs, reason = runs_to_decide(LEVELS, [0.05, 0.267, 1.0], [0.01, 0.27, 0.0], 60, 1e-6)
    assert math.isnan(runs) and "percentile bounds straddle the requirement" in reason


def test_no_number_of_runs_decides_a_crossing_between_levels_around_the_requirement():
    runs, reason = runs_to_decide([0.0, 0.5e-6, 1.5e-6], [0.05, 0.5, 1.0], [0.01, 0.05, 0.0], 100, 1e-6)
    assert math.isnan(runs) and "a sweep level at the requirement is needed" in reason
    runs, reason = runs_to_decide(LEVELS, [0.05, 0.95, 1.0], [0.01, 0.02, 0.0], 100, 1e-6)  # exactly on the line
    assert math.isnan(runs) and "on the 95 % line" in reason


def test_zero_of_350_runs_beyond_a_1_percent_limit_is_decided_at_368():
    """0 of 350: the exact upper bound 1 - 0.025^(1/350) = 1.05 % > 1 % (undetermined); at 368 runs with none beyond
    it is 0.997 % (met), at 367 still 1.0001 %."""
    assert _fraction_interval(0, 350, 0.95)[1] > 0.01
    assert fraction_runs_to_decide(0, 350, 0.01) == 368
    assert _fraction_interval(0, 368, 0.95)[1] <= 0.01 < _fraction_interval(0, 367, 0.95)[1]
    # a share above the allowed one is decided not met once the lower bound clears it
    runs = int(fraction_runs_to_decide(3, 100, 0.01))  # the share held at 3 %: k = 0.03 N (beta quantiles)
    assert _fraction_bounds(0.03 * runs, runs, 0.95)[0] >= 0.01 > _fraction_bounds(0.03 * (runs - 1), runs - 1, 0.95)[0]
    assert math.isnan(fraction_runs_to_decide(1, 100, 0.01))  # exactly the allowed share: never decided


def _sweep(rng, runs: int, levels, spread: float) -> xr.Dataset:
    """A backlash sweep whose feature is the level plus Gaussian spread."""
    names = [f"b{k}" for k in range(len(levels))]
    values = np.array([level + rng.normal(0, spread, runs) for level in levels])
    spec = {"spec": {"name": "s", "datasets": [{"name": n, "conditions": {"backlash": b}}
                                               for n, b in zip(names, levels, strict=True)],
                     "observability": {"sweep": names}}}
    return xr.Dataset(
        {"f": (("dataset", "run"), values, {"role": "feature", "units": "m"}),
         "p.x": (("dataset", "run"), rng.uniform(-1, 1, values.shape), {"role": "sampled", "units": "1"}),
         "status": (("dataset", "run"), np.full(values.shape, "ok", dtype=object)),
         "condition_backlash": ("dataset", np.asarray(levels), {"units": "m"})},
        coords={"dataset": names, "run": np.arange(runs)}, attrs={"spec_json": json.dumps(spec)})


def test_the_analysis_stores_the_runs_for_an_undetermined_verdict():
    """A level at the requirement detected with about 95 %: 60 runs cannot tell, the analysis states how many
    would (more than 60), with the level that decides."""
    results = _sweep(np.random.default_rng(3), 60, (0.0, 1e-6, 2e-6), 0.30e-6)
    analysis = analysis_dataset(results, n_boot=400, sensitivity_boot=10)
    assert str(analysis["requirement_verdict"].sel(feature="f").item()) == "undetermined"
    needed = float(analysis["runs_to_decide"].sel(feature="f"))
    reason = str(analysis["runs_to_decide_reason"].sel(feature="f").item())
    assert 60 < needed < 1e6 and "of the 1 µm (b1) level" in reason
    assert analysis["runs_to_decide"].attrs["units"] == "1"
    decided = analysis_dataset(_sweep(np.random.default_rng(3), 60, (0.0, 1e-6, 2e-6), 0.05e-6), n_boot=200,
                               sensitivity_boot=10)
    assert str(decided["requirement_verdict"].sel(feature="f").item()) == "met"
    assert math.isnan(float(decided["runs_to_decide"].sel(feature="f")))
