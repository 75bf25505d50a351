"""The friction-convergence study's step rule and at-rest figures (app.studies.friction_convergence), without runs."""

import numpy as np
import pytest
import xarray as xr

import twin
from app.studies import friction_convergence as fc

PARAMS = twin.load_parameters()


@pytest.mark.parametrize("seal", fc.SEAL_THRESHOLDS)
@pytest.mark.parametrize("guide", fc.GUIDE_THRESHOLDS)
def test_the_step_divides_the_drive_period_and_keeps_the_friction_mode_inside_rk4s_reach(seal, guide):
    dt = fc.stable_step(seal, guide, PARAMS)
    assert 125e-6 / dt == round(125e-6 / dt)           # a power-of-two fraction of the drive period
    eigenvalue = max(400.0 / (seal * 7.5), 12.0 / (guide * 8.0))   # F_s / (v_th m) of the seal and the guides
    assert eigenvalue * dt <= fc.STEP_MARGIN * fc.RK4_REAL_REACH
    assert dt == fc.BASE_STEP or eigenvalue * 2 * dt > fc.STEP_MARGIN * fc.RK4_REAL_REACH   # the largest such


def test_plan_runs_every_seal_point_before_the_guides_and_pairs_the_seeds():
    plan = fc.study_plan()
    seal_rows = [row for row in plan if row[3] == fc.GUIDE_THRESHOLDS[0]]
    assert plan[:len(seal_rows)] == seal_rows
    assert len(plan) == len(set(plan)) == len(fc.DATASETS) * len(fc.SEEDS) * (
        len(fc.SEAL_THRESHOLDS) + len(fc.GUIDE_THRESHOLDS) - 1)


def test_at_rest_figures_take_only_the_samples_where_the_screw_stands_still():
    time = np.arange(6) * 1e-3
    screw = np.array([0.0, 0.0, 0.0, 1e-5, 2e-5, 2e-5])      # moves (10 mm/s) at samples 3 and 4
    ds = xr.Dataset({"screw_equivalent_position": ("time", screw),
                     "external_force": ("time", [3.0, -4.0, 0.0, 100.0, 100.0, 0.0]),
                     "force_demand": ("time", np.zeros(6)),
                     "nut1_speed": ("time", [1e-3, -1e-3, 0.0, 0.5, 0.5, 2e-3])}, coords={"time": time})
    force, speed_rms, speed_peak = fc.at_rest_figures(ds)
    assert force == pytest.approx(np.sqrt((9 + 16 + 0 + 0) / 4))
    assert speed_rms == pytest.approx(np.sqrt((1e-6 + 1e-6 + 0 + 4e-6) / 4))
    assert speed_peak == pytest.approx(2e-3)
