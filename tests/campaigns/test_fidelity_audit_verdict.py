"""The fidelity audit's verdict per data set and feature, on synthetic paired runs with known shifts: what
compare_fidelity stores, and that results.nc's attributes carry the same statements verbatim."""

import numpy as np
import pytest
import xarray as xr

from campaigns.comparison import paired_shift_verdict
from campaigns.fidelity_audit import (
    MEAN_SHIFT_TOLERANCE,
    compare_fidelity,
    full_fidelity_variant,
    has_automatic_choice,
    numerical_floors,
    summary_attrs,
)
from campaigns.scene_audit import THESIS_SPEC
from campaigns.spec import load_spec

UM = 1e-6
RUNS = 12
#: data set -> (paired shift mean, its standard deviation, failed runs): the verdict each must get
CASES = {
    "inside": (0.01 * UM, 0.02 * UM, 0, "met"),
    "outside": (0.4 * UM, 0.05 * UM, 0, "not met"),
    "straddling": (0.1 * UM, 0.2 * UM, 0, "undetermined"),
    "within_floor": (0.25 * UM, 0.05 * UM, 0, "undetermined"),  # beyond 0.1 um, within 0.1 + its 0.3 um floor
    "too_few": (0.0, 0.02 * UM, RUNS - 1, "insufficient data"),
}
FLOORS = {("within_floor", "backlash_feature"): 0.3 * UM}


def _pair():
    rng = np.random.default_rng(7)
    full = rng.normal(30 * UM, 0.4 * UM, (len(CASES), RUNS))
    shifts = np.array([mean + sd * rng.standard_normal(RUNS) for mean, sd, _, _ in CASES.values()])
    status = np.full(full.shape, "ok", dtype=object)
    for k, (_, _, failed, _) in enumerate(CASES.values()):
        status[k, :failed] = "failed"

    def results(values, wall):
        return xr.Dataset({"backlash_feature": (("dataset", "run"), values), "status": (("dataset", "run"), status),
                           "wall_time": (("dataset", "run"), np.full(values.shape, wall))},
                          coords={"dataset": list(CASES), "run": np.arange(RUNS)})
    return results(full + shifts, 1.0), results(full, 1.5), shifts


def test_each_synthetic_case_gets_its_verdict_and_the_attributes_print_it_verbatim():
    auto, full, shifts = _pair()
    audit = compare_fidelity(auto, full, ["backlash_feature"], FLOORS)
    for k, (name, (_, _, failed, verdict)) in enumerate(CASES.items()):
        row = audit.sel(dataset=name, feature="backlash_feature")
        floor = FLOORS.get((name, "backlash_feature"), 0.0)
        expected = paired_shift_verdict(shifts[k, failed:], MEAN_SHIFT_TOLERANCE, floor)
        assert row.verdict.item() == verdict == expected.verdict, name
        assert row.statement.item() == expected.statement
        assert float(row.shift_lower) == pytest.approx(expected.lower, nan_ok=True)
    attrs = summary_attrs(audit)
    assert attrs["fidelity_audit"] == ("not met: auto differs from full fidelity (the fidelity rule to fix, or with "
                                       "integrator 'auto' the integrator's choice): outside/backlash_feature")
    for name in CASES:
        statement = audit.statement.sel(dataset=name, feature="backlash_feature").item()
        assert attrs[f"fidelity_audit_{name}"].startswith(f"speedup x1.50; backlash_feature: {statement}; max paired")


def test_without_a_not_met_the_worst_remaining_verdict_is_named():
    auto, full, _ = _pair()
    keep = ["inside", "straddling", "too_few"]
    audit = compare_fidelity(auto.sel(dataset=keep), full.sel(dataset=keep), ["backlash_feature"])
    assert audit.attrs["verdict"] == ("undetermined: the audit's runs cannot resolve the tolerance: "
                                      "straddling/backlash_feature")
    audit = compare_fidelity(auto.sel(dataset=["inside"]), full.sel(dataset=["inside"]), ["backlash_feature"])
    assert audit.attrs["verdict"].startswith("met: ")


def test_the_thesis_data_sets_have_a_measured_floor():
    """campaigns/numerical_floor.toml covers every thesis data set (its conditions are the scene's own)."""
    spec = load_spec(THESIS_SPEC)
    floors = numerical_floors(spec, list(spec.features))
    assert {d for d, _ in floors} == {d.name for d in spec.datasets}
    assert all(floor >= 0 for floor in floors.values())
    # a data set that changes its scene's conditions has no measured floor
    ds2 = spec.datasets[1].model_copy(update={"conditions": {"backlash": 1e-6}})
    moved = spec.model_copy(update={"datasets": [ds2]})
    assert numerical_floors(moved, list(spec.features)) == {}


def test_an_auto_integrator_campaign_is_audited_against_the_default_integrator():
    """The audit's reference run is full fidelity; with the opt-in automatic integrator also the default method (at
    its own step), so the automatic choice of the method is judged by the same rule as that of the levels."""
    spec = load_spec(THESIS_SPEC)
    assert spec.solver.integrator == "rk4"
    kept = full_fidelity_variant(spec, 3)
    assert (kept.solver.fidelity, kept.solver.integrator, kept.runs_per_dataset) == ("full", "rk4", 3)
    auto = spec.model_copy(update={"solver": spec.solver.model_copy(update={"integrator": "auto"})})
    audited = full_fidelity_variant(auto, 3)
    assert (audited.solver.fidelity, audited.solver.integrator, audited.solver.dt) == ("full", "rk4", None)
    explicit = spec.model_copy(update={"solver": spec.solver.model_copy(update={"integrator": "imex_euler"})})
    assert full_fidelity_variant(explicit, 3).solver.integrator == "imex_euler"  # a named method is the user's
    # at full fidelity only the automatic integrator is left to audit
    full = {"fidelity": "full"}
    assert has_automatic_choice(spec) and has_automatic_choice(auto)
    assert not has_automatic_choice(spec.model_copy(update={"solver": spec.solver.model_copy(update=full)}))
    assert has_automatic_choice(auto.model_copy(update={"solver": auto.solver.model_copy(update=full)}))
