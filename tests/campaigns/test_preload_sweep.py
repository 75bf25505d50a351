"""The observability sweep generalised to a preload-loss sweep (issue 18): spec checks and a known answer."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from campaigns.analysis.observability import observability_sweep
from campaigns.bench.campaign import load_spec
from campaigns.runner.spec import SpecError

SPEC = Path(__file__).parents[2] / "campaigns" / "specs" / "preload_loss.toml"


def test_preload_loss_spec_loads_with_its_reference_and_requirement():
    spec = load_spec(SPEC)
    assert spec.observability.condition == "preload" and spec.observability.reference == "p1000"
    assert spec.observability.requirement == 200.0
    assert "drag_torque_feature" in spec.features


def test_preload_sweep_without_reference_or_requirement_is_rejected(tmp_path):
    text = SPEC.read_text().replace('reference = "p1000"\n', "").replace("requirement = 200.0\n", "")
    bad = tmp_path / "bad.toml"
    parent = SPEC.parent / "thesis_backlash.toml"
    bad.write_text(text.replace('extends = "thesis_backlash.toml"', f'extends = "{parent}"'))
    with pytest.raises(SpecError) as error:
        load_spec(bad)
    message = str(error.value)
    assert "observability.reference" in message and "observability.requirement" in message


def _results(preloads, runs=200, slope=1e-4, noise=0.004, seed=1):
    """Synthetic results: a feature = slope * preload + Gaussian noise, every run ok."""
    rng = np.random.default_rng(seed)
    names = [f"p{p:.0f}" for p in preloads]
    values = np.array([slope * p + noise * rng.standard_normal(runs) for p in preloads])
    return xr.Dataset(
        {"feature": (("dataset", "run"), values),
         "status": (("dataset", "run"), np.full(values.shape, "ok", dtype=object)),
         "condition_preload": ("dataset", np.array(preloads, dtype=float))},
        coords={"dataset": names}), names


def test_minimum_detectable_preload_loss_known_answer():
    """Feature 1e-4 N m per N of preload, noise sigma 4e-3 N m: the reference's 5 % false-alarm threshold is
    1.645 sigma below its mean (the feature falls with the loss), 95 % detection needs the loss to move the mean a
    further 1.645 sigma: 2 x 1.645 x 4e-3 / 1e-4 = 132 N. With sweep levels 0, 100, 200, ... the estimate lies in
    (100, 200] and the 200 N requirement is met (its bound at most 200 N)."""
    results, names = _results([1000.0, 900.0, 800.0, 600.0, 400.0])
    found = observability_sweep(results, "feature", names, condition="preload", reference="p1000", requirement=200.0,
                                requirement_source="test", n_boot=300, seed=0)
    estimate = float(found["minimum_detectable_preload_loss"])
    assert 100.0 < estimate <= 200.0
    assert estimate == pytest.approx(2 * 1.645 * 4e-3 / 1e-4, rel=0.25)
    assert str(found["requirement_verdict"].values) == "met"
    statement = str(found["requirement_statement"].values)
    assert statement.startswith("met: minimum detectable preload loss") and "against the 200 N requirement" in statement
    np.testing.assert_array_equal(found["sweep_preload_loss"].values, [0.0, 100.0, 200.0, 400.0, 600.0])
