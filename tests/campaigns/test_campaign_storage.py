"""Storage: results.nc round trip, schema and attributes, atomic chunk files."""

from __future__ import annotations

import json

import numpy as np
import xarray as xr
from campaign_helpers import SYNTHETIC_SPEC, load

from campaigns.runner.files import CONVENTIONS


def test_results_round_trip(reference_results, tmp_path):
    with xr.open_dataset(reference_results, engine="netcdf4") as first:
        first.load()
    copy = tmp_path / "copy.nc"
    first.to_netcdf(copy, engine="netcdf4")
    with xr.open_dataset(copy, engine="netcdf4") as second:
        xr.testing.assert_identical(first, second)


def test_results_schema(reference_results):
    spec = load(SYNTHETIC_SPEC)
    with xr.open_dataset(reference_results) as ds:
        assert dict(ds.sizes) == {"dataset": 4, "run": 40, "trace_run": 2, "trace_time": 11}
        assert list(ds["dataset"].values) == ["ds2", "ds4", "ds6", "ds5"]
        for d in spec.distributions():
            assert ds[d.target].dims == ("dataset", "run")
            assert ds[d.target].attrs["units"] == d.unit and ds[d.target].attrs["role"] == "sampled"
        for name in ("backlash_feature", "backlash_feature_true", "status", "failure_reason", "t_reached", "wall_time"):
            assert ds[name].dims == ("dataset", "run")
        assert ds["backlash_feature"].attrs["units"] == "m" and ds["t_reached"].attrs["units"] == "s"
        assert ds["condition_backlash"].sel(dataset="ds6") == 5e-6
        assert ds["trace_nut1_position"].dims == ("dataset", "trace_run", "trace_time")
        assert ds["trace_nut1_position"].attrs["units"] == "m"
        # the kept trace is the run's own: its last sample is the true feature (synthetic model)
        np.testing.assert_allclose(ds["trace_nut1_position"][:, :, -1], ds["backlash_feature_true"][:, :2])
        assert ds.attrs["Conventions"] == CONVENTIONS
        assert json.loads(ds.attrs["spec_json"]) == spec.canonical()
        assert ds.attrs["spec_hash"] == spec.spec_hash()
        assert int(ds.attrs["root_seed_entropy"]) == spec.root_seed
        assert "numpy" in json.loads(ds.attrs["package_versions"])


def test_no_stray_temporary_files(reference_results):
    assert not list(reference_results.parent.rglob("*.tmp"))
    assert len(list(reference_results.parent.glob("chunks/*/d*.npz"))) >= 4
