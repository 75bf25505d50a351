"""Issue 30, point 3: ``twin export`` writes tidy tables that CSV, Excel and MATLAB readers open, units in the headers,
under the one write rule (never over a campaign's own files, nothing existing without --force)."""

from __future__ import annotations

import errno
import os
import shutil
from pathlib import Path

import numpy as np
import openpyxl
import pandas as pd
import pytest
import scipy.io
import xarray as xr
from cli_helpers import refused_in_one_line

import campaigns
import campaigns.runner.files
from app.cli import main


@pytest.fixture(scope="module")
def analysed(reference_results, tmp_path_factory):
    """A copy of the synthetic reference campaign (results.nc only: the rule reads names) with its analysis."""
    out = tmp_path_factory.mktemp("export") / "campaign"
    out.mkdir()
    shutil.copy(reference_results, out / "results.nc")
    campaigns.analyze(out / "results.nc")
    return out / "results.nc"


def test_csv_tables_open_in_pandas_with_units_in_the_headers(analysed, tmp_path, capsys):
    assert main(["export", str(analysed), "--format", "csv", "--out", str(tmp_path / "csv")]) == 0
    with xr.open_dataset(analysed) as results:
        n_datasets, n_runs = results.sizes["dataset"], results.sizes["run"]
        stored = results["backlash_feature"].sel(dataset=str(results["dataset"].values[1])).values
        sampled = [str(v) for v in results.data_vars if results[v].attrs.get("role") == "sampled"]
        units = {v: results[v].attrs["units"] for v in sampled}
    runs = pd.read_csv(tmp_path / "csv" / "runs.csv")
    assert len(runs) == n_datasets * n_runs  # one row per run
    assert {"dataset", "run", "status", "backlash_feature [m]"} <= set(runs.columns)
    assert {f"{name} [{units[name]}]" for name in sampled} <= set(runs.columns)
    second = runs[runs["dataset"] == runs["dataset"].unique()[1]].sort_values("run")
    np.testing.assert_array_equal(second["backlash_feature [m]"].to_numpy(), stored)
    stats = pd.read_csv(tmp_path / "csv" / "features.csv")
    assert {"dataset", "feature", "feature units", "n_used [1]", "feature_mean [m]"} <= set(stats.columns)
    verdicts = pd.read_csv(tmp_path / "csv" / "verdicts.csv")
    assert set(verdicts["requirement_verdict"]) <= {"met", "not met", "undetermined", "insufficient data"}
    sensitivity = pd.read_csv(tmp_path / "csv" / "sensitivity.csv")
    assert {"spearman_ci_lower [1]", "spearman_ci_upper [1]", "first_order_index_flag"} <= set(sensitivity.columns)
    assert "wrote" in capsys.readouterr().out


def test_xlsx_opens_in_openpyxl_and_mat_in_scipy(analysed, tmp_path):
    assert main(["export", str(analysed), "--format", "xlsx", "--out", str(tmp_path)]) == 0
    book = openpyxl.load_workbook(tmp_path / "campaign.xlsx", read_only=True)
    assert {"runs", "features", "sensitivity", "detection", "verdicts"} <= set(book.sheetnames)
    header = next(book["runs"].iter_rows(max_row=1, values_only=True))
    assert "backlash_feature [m]" in header
    rows = book["runs"].max_row - 1
    assert main(["export", str(analysed), "--format", "mat", "--out", str(tmp_path)]) == 0
    mat = scipy.io.loadmat(tmp_path / "campaign.mat", simplify_cells=True)
    runs = mat["runs"]
    assert len(runs["backlash_feature"]) == rows
    assert "backlash_feature [m]" in list(runs["columns"])  # the units travel with the struct
    assert "synthetic_gain" in runs  # dots become underscores in MATLAB field names


def test_export_keeps_the_write_rule(analysed, tmp_path, capsys):
    out = tmp_path / "csv"
    assert main(["export", str(analysed), "--out", str(out)]) == 0
    before = (out / "runs.csv").read_bytes()
    assert main(["export", str(analysed), "--out", str(out)]) == 2
    assert "already exists; pass --force" in capsys.readouterr().err
    assert (out / "runs.csv").read_bytes() == before
    assert main(["export", str(analysed), "--out", str(out), "--force"]) == 0
    # into the campaign's own chunks directory: refused even with --force
    (analysed.parent / "chunks" / "0123456789abcdef").mkdir(parents=True)
    (analysed.parent / "spec.json").write_text("{}")
    try:
        assert main(["export", str(analysed), "--out", str(analysed.parent / "chunks"), "--force"]) == 2
        assert "no command writes over a campaign's own files" in capsys.readouterr().err
    finally:
        (analysed.parent / "spec.json").unlink()
        shutil.rmtree(analysed.parent / "chunks")


def _fail_midway(monkeypatch, errno_code: int, *, on_call: int = 1):
    """``DataFrame.to_csv`` writes half its text, then the disk refuses (as a full disk does), on call ``on_call``."""
    original = pd.DataFrame.to_csv
    calls = []

    def to_csv(self, path, **kwargs):
        calls.append(path)
        if len(calls) < on_call:
            return original(self, path, **kwargs)
        text = original(self, None, **kwargs)
        with open(path, "w") as f:
            f.write(text[: len(text) // 2])
        raise OSError(errno_code, os.strerror(errno_code), str(path))

    monkeypatch.setattr(pd.DataFrame, "to_csv", to_csv)


def test_a_full_disk_leaves_the_previous_export_whole(analysed, tmp_path, capsys, monkeypatch):
    """Issue 39: the export wrote in place; a full disk left a truncated runs.csv under its name, and a failing
    --force export destroyed the previous one."""
    out = tmp_path / "csv"
    assert main(["export", str(analysed), "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    capsys.readouterr()
    _fail_midway(monkeypatch, errno.ENOSPC)
    refused_in_one_line(capsys, ["export", str(analysed), "--out", str(out), "--force"],
                        f"cannot write {out / 'runs.csv'}", "the disk is full", "Nothing was replaced")
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # every file as it was, no temporary left


def test_a_failure_after_some_tables_names_those_written_and_leaves_no_truncated_one(analysed, tmp_path, capsys,
                                                                                   monkeypatch):
    _fail_midway(monkeypatch, errno.ENOSPC, on_call=2)
    out = tmp_path / "csv"
    refused_in_one_line(capsys, ["export", str(analysed), "--out", str(out)], f"cannot write {out / 'features.csv'}",
                        "(written before it: runs.csv)")
    assert sorted(p.name for p in out.iterdir()) == ["runs.csv"]
    assert len(pd.read_csv(out / "runs.csv")) > 0  # whole


@pytest.mark.parametrize("fmt", ["csv", "xlsx", "mat"])
def test_a_read_only_directory_is_one_line(analysed, tmp_path, capsys, monkeypatch, fmt):
    """Tests run as root, where chmod does not stop writes: the refusal is simulated where the OS gives it."""
    def refused(*args, **kwargs):
        raise PermissionError(errno.EACCES, "Permission denied")

    out = tmp_path / "ro"
    out.mkdir()
    monkeypatch.setattr(campaigns.runner.files.tempfile, "mkstemp", refused)
    refused_in_one_line(capsys, ["export", str(analysed), "--format", fmt, "--out", str(out)],
                        "cannot write", "Permission denied")
    assert not list(out.iterdir())
    monkeypatch.setattr(Path, "mkdir", refused)
    refused_in_one_line(capsys, ["export", str(analysed), "--format", fmt, "--out", str(tmp_path / "new")],
                        f"cannot create the directory {tmp_path / 'new'}: Permission denied")


def test_a_truncated_analysis_beside_good_results_is_one_line_naming_the_remedy(analysed, tmp_path, capsys):
    campaign = tmp_path / "campaign"
    campaign.mkdir()
    shutil.copy(analysed, campaign / "results.nc")
    whole = (analysed.parent / "analysis.nc").read_bytes()
    (campaign / "analysis.nc").write_bytes(whole[: len(whole) // 2])
    refused_in_one_line(capsys, ["export", str(campaign / "results.nc"), "--out", str(tmp_path / "csv")],
                        f"{campaign / 'analysis.nc'}: cannot be read as a netCDF file", "is it complete?",
                        f"`twin campaign analyze {campaign / 'results.nc'} --force` writes it again")
    assert not (tmp_path / "csv").exists()  # before any work
