"""scripts/findings_tables.py on a sweep of another quantity than backlash (a preload-loss sweep)."""

import importlib.util
from pathlib import Path

import numpy as np
import xarray as xr


def _findings_tables():
    path = Path(__file__).parents[2] / "scripts" / "findings_tables.py"
    spec = importlib.util.spec_from_file_location("findings_tables", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_preload_sweep_prints_its_levels_not_the_interval_variables(capsys):
    # the analysis of a preload-loss sweep holds two sweep_ variables over sweep_point besides the swept quantity
    # (the detection probability and its interval); the table must label the columns with the preload loss
    points = ["p1000", "p800", "p600"]
    analysis = xr.Dataset(
        {
            "sweep_detection_probability": (("feature", "sweep_point"), np.array([[0.05, 0.5, 1.0]])),
            "sweep_detection_probability_ci": (("feature", "sweep_point", "bound"), np.zeros((1, 3, 2))),
            "sweep_preload_loss": (("sweep_point",), np.array([0.0, 200.0, 400.0])),
            "requirement_statement": (("feature",), np.array(["not met: between 200 and 400 N"], dtype=object)),
        },
        coords={"feature": ["drag_torque_feature"], "sweep_point": points, "bound": ["lower", "upper"]},
        attrs={"requirement_units": "N"},
    )
    _findings_tables().observability(analysis)
    out = capsys.readouterr().out
    assert "| feature | p1000 (0 N) | p800 (200 N) | p600 (400 N) |" in out
    assert "| drag_torque_feature | 0.05 | 0.50 | 1.00 |" in out
