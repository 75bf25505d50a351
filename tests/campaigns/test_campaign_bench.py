"""Integration with the bench twin: the shipped specs against its catalog, and two real runs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import campaigns

twin = pytest.importorskip("twin", reason="the bench twin (twin package) is not importable")
if not hasattr(twin, "simulate"):
    pytest.skip("twin.simulate does not exist yet", allow_module_level=True)

SPECS = Path(campaigns.__file__).parent / "specs"


@pytest.mark.parametrize("name", ["thesis_backlash.toml", "demo.toml"])
def test_shipped_specs_validate_against_the_bench(name):
    spec = campaigns.load_spec(SPECS / name)
    assert len(spec.distributions()) == 38


def test_two_real_bench_runs(tmp_path):
    """Data sets 2 (80 um) and 4 (0 um), one run each, through twin.simulate in the sandbox."""
    path = tmp_path / "two_runs.toml"
    path.write_text(
        f'extends = "{SPECS / "thesis_backlash.toml"}"\n'
        'name = "two_runs"\nruns_per_dataset = 1\n'
        '[observability]\nsweep = ["ds4", "ds2"]\n'
        '[traces]\nruns_per_dataset = 1\n'
        '[[datasets]]\nname = "ds2"\nscene = "ds2"\nconditions = { backlash = 80e-6, preload = 0.0 }\n'
        '[[datasets]]\nname = "ds4"\nscene = "ds4"\nconditions = { backlash = 0.0, preload = 0.0 }\n'
    )
    results = campaigns.run_campaign(campaigns.load_spec(path), tmp_path / "out", workers=2, progress=False)
    with xr.open_dataset(results) as ds:
        reasons = dict(zip(ds["dataset"].values, ds["failure_reason"].values[:, 0]))
        assert (ds["status"] == "ok").all(), f"runs not ok: {reasons}"
        true = ds["backlash_feature_true"].sel(run=0)
        assert float(true.sel(dataset="ds2")) > float(true.sel(dataset="ds4"))
        assert math.isfinite(float(ds["backlash_feature"].sel(dataset="ds2", run=0)))
        assert ds["trace_nut1_position"].attrs["units"] == "m"
    analysis = campaigns.analyze(results)
    with xr.open_dataset(analysis) as a:
        assert list(a["sweep_point"].values) == ["ds4", "ds2"]
    # the sandboxed campaign run, replayed alone in this process, gives the same bits and its full series
    from campaigns.replay import replay_run

    replayed = replay_run(results, "ds2", 0)
    with xr.open_dataset(results) as ds:
        for feature in ("backlash_feature", "backlash_feature_true"):
            assert replayed[feature].values.tobytes() == ds[feature].sel(dataset="ds2", run=0).values.tobytes()
        assert replayed.sizes["time"] == 10_001  # 10 s at 1 ms, undecimated (the campaign kept every 10th)
        np.testing.assert_array_equal(replayed["nut1_position"].values[::10],
                                      ds["trace_nut1_position"].sel(dataset="ds2", trace_run=0).values)


def test_campaign_records_fidelity_and_its_audit(tmp_path):
    """auto by default: each data set's configuration and the paired audit against full fidelity land in results.nc."""
    path = tmp_path / "audited.toml"
    path.write_text(
        f'extends = "{SPECS / "thesis_backlash.toml"}"\n'
        'name = "audited"\nruns_per_dataset = 2\n[observability]\nsweep = []\n'
        '[fidelity_audit]\nruns = 2\n'
        '[[datasets]]\nname = "ds4"\nscene = "ds4"\nconditions = { backlash = 0.0, preload = 0.0 }\n'
    )
    results = campaigns.run_campaign(campaigns.load_spec(path), tmp_path / "out", workers=1, progress=False)
    with xr.open_dataset(results) as ds:
        assert ds.attrs["fidelity_requested"] == '"auto"'
        assert "current_loop=ideal" in ds.attrs["fidelity_ds4"] and "encoders=full" in ds.attrs["fidelity_ds4"]
        assert ds.attrs["fidelity_audit_runs"] == "2"
        assert ds.attrs["fidelity_audit_ds4"].startswith("speedup x")
        assert "backlash_feature: mean shift" in ds.attrs["fidelity_audit_ds4"]
    with xr.open_dataset(tmp_path / "out" / "fidelity_audit" / "fidelity_audit.nc") as audit:
        assert audit.attrs["runs"] == 2
        assert float(np.abs(audit.mean_shift).max()) < 0.1e-6


def test_spec_fidelity_is_validated(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(f'extends = "{SPECS / "demo.toml"}"\n[solver]\nfidelity = {{ gearbox = "full", contact = "rigid" }}\n')
    with pytest.raises(campaigns.SpecError) as info:
        campaigns.load_spec(path)
    assert "unknown subsystem 'gearbox'" in str(info.value) and "contact: level 'rigid'" in str(info.value)
