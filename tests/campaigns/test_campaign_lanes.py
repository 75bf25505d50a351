"""The bench run model's lane groups (:attr:`campaigns.bench.adapter.BenchModel.lanes`) change no number: a group of
its width gives each run the features of the same runs in groups of the twin's default width (8) and alone."""

from __future__ import annotations

import dataclasses

import campaigns
from campaigns.bench.adapter import simulate_group, simulate_one, simulate_run
from campaigns.runner.execution import build_request
from campaigns.runner.sampling import sample


def test_a_full_lane_group_gives_the_features_of_narrower_groups_and_of_each_run_alone():
    spec = campaigns.load_spec(campaigns.__path__[0] + "/specs/thesis_backlash.toml", runs=simulate_run.lanes)
    assert simulate_run.lanes == 16
    samples = sample(spec)
    d = [dataset.name for dataset in spec.datasets].index("ds2")
    requests = [dataclasses.replace(build_request(spec, samples, d, i), trace_variables=(),
                                    outputs=tuple(spec.features), solver={**spec.solver.model_dump(), "duration": 0.3})
                for i in range(simulate_run.lanes)]

    def bits(result: dict) -> dict:  # exact, NaN included (a short run may not reach a feature's motion)
        return {name: float(value).hex() for name, value in result["features"].items()}

    wide = simulate_group(requests)
    narrow = simulate_group(requests[:8]) + simulate_group(requests[8:])
    assert [bits(r) for r in wide] == [bits(r) for r in narrow]
    assert all(r["status"] == "ok" for r in wide) and bits(wide[0])
    assert bits(wide[3]) == bits(simulate_one(requests[3]))
