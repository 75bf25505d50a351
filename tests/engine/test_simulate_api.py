"""The simulate entry point: dataset contents, bad options, and the divergence guard."""

import numpy as np
import pytest

import twin
from twin.errors import OptionError, SimulationFailed

REQUIRED = ["position_demand", "nut1_position", "nut2_position", "screw_angle", "screw_equivalent_position",
            "motor_current", "motor_torque", "winding_temperature", "preload_force", "external_force"]


@pytest.fixture(scope="module")
def short_nominal():
    return twin.simulate("nominal", duration=1.2)


def test_dataset_signals_with_units(short_nominal):
    ds = short_nominal
    assert ds.attrs["status"] == "ok" and ds.attrs["t_reached"] == pytest.approx(1.2)
    assert ds.time.attrs["units"] == "s"
    for name in REQUIRED + ["backlash_feature_true"]:
        assert name in ds, name
        assert ds[name].attrs["units"], name
    assert ds.backlash_feature_true.ndim == 0 and ds.backlash_feature_true.attrs["units"] == "m"
    assert np.all(np.isfinite(ds.to_array()))


def test_bad_options_listed_before_running():
    with pytest.raises(OptionError) as info:
        twin.simulate("nominal", integrator="euler_forward", dt=3e-5, curvature="flat")
    text = str(info.value)
    assert "integrator" in text and "dt" in text and "curvature" in text


def test_same_inputs_same_numbers():
    a = twin.simulate("ds2", duration=0.8)
    b = twin.simulate("ds2", duration=0.8)
    assert float(a.backlash_feature_true) == float(b.backlash_feature_true)
    np.testing.assert_array_equal(a.nut1_position.values, b.nut1_position.values)


def test_guard_reports_unstable_step_as_data():
    """A step beyond RK4's stability limit for the contact (~4e-5 s) is caught and reported, not silent."""
    ds = twin.simulate("nominal", dt=1.25e-4, throw=False, duration=1.0)
    assert ds.attrs["status"] == "diverged"
    assert ds.attrs["failure_reason"]
    assert 0 < ds.attrs["t_reached"] < 1.0
    assert np.isnan(float(ds.backlash_feature_true))
    with pytest.raises(SimulationFailed, match="diverged"):
        twin.simulate("nominal", dt=1.25e-4, duration=1.0)


def test_iso_curvature_selectable():
    a = twin.simulate("ds5", duration=0.6, curvature="iso")
    b = twin.simulate("ds5", duration=0.6, curvature="thesis")
    # at the 5.7 deg helix angle the two curvature formulas give nearly the same stiffness
    assert float(a.backlash_feature_true) == pytest.approx(float(b.backlash_feature_true), rel=1e-3, abs=1e-9)
