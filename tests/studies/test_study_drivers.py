"""The study drivers behind `twin accuracy`: the python-control baseline, the stability map and the study
orchestration, each on a tiny problem with numbers checked against an oracle."""

import pandas as pd
import pytest
import xarray as xr

import twin
from app.studies import accuracy
from app.studies.control_baseline import compare
from app.studies.stability import THEORY, loaded_scene, loaded_state, stability_map
from twin.engine.linearize import highest_frequency, jacobian


@pytest.fixture(scope="module")
def baseline():
    return {row["method"]: row for row in compare()}


def test_control_baseline_agrees_with_the_radau_reference(baseline):
    """The same open-loop problem four ways: the tight Radau solution is the reference (error 0); RK4 at
    15.6 us lies on it to < 1 nm, the first-order semi-implicit Euler and python-control's RK45 at rtol 1e-6
    to < 1 um, the RK4 error being far below the semi-implicit Euler's (order 4 against 1)."""
    errors = {name.split(" (")[0]: row["error"] for name, row in baseline.items()}
    assert set(errors) == {"scipy_radau", "control.input_output_response", "compiled rk4",
                           "compiled semi_implicit_euler"}
    assert errors["scipy_radau"] == 0.0
    assert errors["compiled rk4"] < 1e-9
    assert errors["compiled rk4"] < errors["compiled semi_implicit_euler"] / 10 < 1e-7
    assert 0.0 < errors["control.input_output_response"] < 1e-6


def test_stability_map_measures_the_theoretical_limit():
    """One loaded case (1 kN preload, 8 kN): the bisected RK4 limit lies within 15 % of 2.8 / omega_max, with
    omega_max the Jacobian's largest eigenvalue modulus at the loaded state, computed here independently."""
    data = stability_map(methods=("rk4",), preloads=(1000.0,), forces=(8000.0,), masses=(), progress=lambda line: None)
    assert data.sizes["case"] == 1 and float(data.preload[0]) == 1000.0 and float(data.force[0]) == 8000.0
    scene, params = loaded_scene(1000.0, 8000.0), twin.load_parameters()
    model, x0, inputs = loaded_state(scene, params)
    omega = highest_frequency(jacobian(model, x0, t=scene.duration, u=inputs))
    assert float(data.omega_max[0]) == pytest.approx(omega, rel=1e-9)
    assert float(data.theory_rk4[0]) == pytest.approx(THEORY["rk4"] / omega, rel=1e-12)
    assert float(data.limit_rk4[0]) == pytest.approx(THEORY["rk4"] / omega, rel=0.15)
    assert data.limit_rk4.attrs["units"] == "s"


def test_run_accuracy_writes_the_study_and_its_charts(tmp_path, monkeypatch):
    """A tiny study (one scene of 50 ms, two RK4 steps, one tolerance): the stored errors shrink with the step
    at RK4's order, the baseline table is compare()'s, and the charts are drawn from the stored data."""
    monkeypatch.setattr(accuracy, "QUICK", {"steps": (6.25e-5, 3.125e-5), "tolerances": (1e-6,), "repeats": 1,
                                            "methods": ("rk4",), "baselines": ("scipy_lsoda",)})
    lines = []
    paths = accuracy.run_accuracy(tmp_path, "ds4", 0.05, quick=True, stability=False, progress=lines.append)
    assert set(paths) == {"work_precision"} and paths["work_precision"].stat().st_size > 10_000
    with xr.open_dataset(tmp_path / "work_precision.nc") as study:
        study = study.load()
    # per panel: the default configuration's one point, two RK4 steps, one scipy tolerance
    assert study.sizes["run"] == 8 and set(study.panel.values) == {"quantizers_off", "quantizers_on"}
    assert (study.method == "default (rk4, quasi-static screw axial)").sum() == 2
    assert (study.status == "ok").all()
    rk4 = study.where((study.method == "rk4") & (study.panel == "quantizers_off"), drop=True).sortby("dt")
    fine, coarse = rk4.current_rms_error.values
    assert coarse / fine > 2.0**3  # RK4 at order >= 3 over one halving (measured 2^5.5, pre-asymptotic)
    assert (tmp_path / "work_precision.csv").stat().st_size > 0
    table = pd.read_csv(tmp_path / "control_baseline.csv")
    assert len(table) == 4 and table.loc[table.method.str.startswith("scipy_radau"), "error"].item() == 0.0
    assert table.loc[table.method.str.startswith("compiled rk4"), "error"].item() < 1e-9
    assert any("input_output_response" in line for line in lines)
