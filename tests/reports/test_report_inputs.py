"""Missing, corrupt or inconsistent input gives a ReportError naming the file, never a traceback of the internals."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
import xarray as xr

import reports
from reports import ReportError


def test_missing_results(tmp_path):
    missing = tmp_path / "nope" / "results.nc"
    with pytest.raises(ReportError, match="file not found") as info:
        reports.build_report(missing, out_dir=tmp_path / "out")
    assert info.value.path == missing
    assert str(missing) in str(info.value)
    assert not (tmp_path / "out").exists()


def test_garbage_results(tmp_path):
    path = tmp_path / "results.nc"
    path.write_bytes(b"this is not a netCDF file\n" * 20)
    with pytest.raises(ReportError, match="cannot be read as a netCDF campaign results file") as info:
        reports.build_report(path, out_dir=tmp_path / "out")
    assert info.value.path == path


def test_truncated_results(campaign, tmp_path):
    path = tmp_path / "results.nc"
    path.write_bytes(campaign.read_bytes()[: campaign.stat().st_size // 2])
    with pytest.raises(ReportError, match="is it complete") as info:
        reports.build_report(path, out_dir=tmp_path / "out")
    assert info.value.path == path


def test_netcdf_that_is_not_campaign_results(tmp_path):
    path = tmp_path / "signals.nc"
    xr.Dataset({"motor_current": ("time", np.zeros(3))}).to_netcdf(path)
    with pytest.raises(ReportError,
                       match="not a campaign results file: variable 'status' missing.*no feature variable"):
        reports.build_report(path, out_dir=tmp_path / "out")


def test_missing_analysis(campaign, tmp_path):
    with pytest.raises(ReportError, match="campaign analysis file not found"):
        reports.build_report(campaign, tmp_path / "analysis.nc", tmp_path / "out")


def test_analysis_of_another_campaign(campaign, tmp_path):
    path = tmp_path / "analysis.nc"
    with xr.open_dataset(campaign.with_name("analysis.nc")) as analysis:
        analysis.load().assign_attrs(source_spec_hash="0" * 64).to_netcdf(path)
    with pytest.raises(ReportError, match="analysis of another campaign") as info:
        reports.build_report(campaign, path, tmp_path / "out")
    assert info.value.path == path


def test_accuracy_study_without_the_expected_variables(campaign, tmp_path):
    path = tmp_path / "work_precision.nc"
    xr.Dataset({"wall_time": ("run", [1.0, 2.0])}).to_netcdf(path)
    with pytest.raises(ReportError, match="not a work-precision study .*feature_error, status, method missing") as info:
        reports.build_report(campaign, out_dir=tmp_path / "out", accuracy_path=path)
    assert info.value.path == path


def test_output_directory_that_is_a_file(campaign, tmp_path):
    blocker = tmp_path / "report"
    blocker.write_text("a file where the report directory should go")
    with pytest.raises(ReportError, match="cannot write the report there") as info:
        reports.build_report(campaign, out_dir=blocker)
    assert info.value.path == blocker


def test_results_alone_are_analysed_in_memory(campaign, tmp_path):
    from reports.inputs import load_inputs

    alone = tmp_path / "results.nc"
    shutil.copyfile(campaign, alone)
    inputs = load_inputs(alone)
    assert inputs.analysis_computed
    assert [f.role for f in inputs.files] == ["results"]
    assert not (tmp_path / "analysis.nc").exists()
    with xr.open_dataset(campaign.with_name("analysis.nc")) as stored:
        xr.testing.assert_allclose(inputs.analysis["spearman"], stored["spearman"])
