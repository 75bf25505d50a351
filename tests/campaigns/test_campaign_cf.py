"""Issue 31, the data files in other tools: the IOOS compliance checker (CF 1.11 and 1.8) finds no high-priority
problem in a campaign's results.nc and analysis.nc, a replayed run, a ``twin simulate --out`` file and a fidelity
audit (but one, on a run's elapsed time: :data:`ELAPSED_TIME_FINDING`); every file declares the one CF version;
cf_xarray-style readers get numeric flags, and unit libraries read every unit; xarray reads a run's time as
seconds (issue 39: not as dates of 1970).

The checker is PyPI's ``compliance-checker`` (its ``cf-units`` wheel bundles the UDUNITS-2 library and database:
nothing to install besides the test extras). It is run in-process, once per file and CF version.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import campaigns
from campaigns.bench.fidelity_audit import compare_fidelity
from campaigns.bench.replay import replay_run
from campaigns.runner.files import CONVENTIONS, write_netcdf

pytest.importorskip("compliance_checker")

#: CF versions checked: the one the files declare, and 1.8 (what many tools still implement).
VERSIONS = (f"cf:{CONVENTIONS.removeprefix('CF-')}", "cf:1.8")
#: The one high-priority finding accepted, on the files with a run's time axis (``twin simulate --out``, a replay):
#: the checker takes a dimension named ``time`` for CF's time axis (its Sec. 5.1 table of names) and asks for
#: ``standard_name = "time"``, which needs units "s since <date>" (CF 4.4). A run's time is seconds from the start
#: of its test, an elapsed time that CF identifies by its unit, not its name (CF 4.4: "a time coordinate is
#: identifiable from its units string alone"); a date unit has xarray and pandas plot a 10 s test against dates of
#: 1970 (docs/campaigns.md, "Replaying one run").
ELAPSED_TIME_FINDING = "Coordinate variable 'time' should have standard_name='time', found: 'None'"


def high_priority_findings(path, version: str, tmp_path) -> list[str]:
    """The compliance checker's high-priority findings on ``path`` (empty: none)."""
    from compliance_checker.runner import CheckSuite, ComplianceChecker

    CheckSuite.load_all_available_checkers()
    report = tmp_path / f"{path.stem}-{version.replace(':', '')}.json"
    ComplianceChecker.run_checker(str(path), [version], 0, "normal", output_filename=str(report),
                                  output_format="json_new")
    result = json.loads(report.read_text())
    findings = []
    for checks in result.values():
        for outcome in checks.values():
            assert not outcome.get("errors"), outcome["errors"]  # the checker itself must not fail on the file
            findings += [f"{item['name']}: {msg}" for item in outcome.get("high_priorities", [])
                         for msg in item["msgs"]]
    return findings


@pytest.fixture(scope="module")
def analysis_file(reference_results, tmp_path_factory):
    return campaigns.analyze(reference_results, tmp_path_factory.mktemp("analysis") / "analysis.nc")


@pytest.fixture(scope="module")
def replay_file(reference_results, tmp_path_factory):
    out = tmp_path_factory.mktemp("replay") / "run.nc"
    replay_run(reference_results, "ds6", 1, out=out)
    return out


@pytest.fixture(scope="module")
def audit_file(reference_results, tmp_path_factory):
    """A fidelity audit of the synthetic campaign against itself (the comparison and its file, no bench runs)."""
    with xr.open_dataset(reference_results) as ds:
        results = ds.load()
    out = tmp_path_factory.mktemp("audit") / "fidelity_audit.nc"
    write_netcdf(compare_fidelity(results, results.isel(run=slice(0, 5)), ["backlash_feature"]), out,
                 title="fidelity audit", history="test")
    return out


@pytest.fixture(scope="module")
def simulate_file(tmp_path_factory):
    out = tmp_path_factory.mktemp("simulate") / "ds4.nc"
    result = subprocess.run([sys.executable, "-m", "app.cli", "simulate", "ds4", "--duration", "0.05", "--out",
                             str(out)], capture_output=True, text=True, timeout=1800)
    assert result.returncode == 0, result.stderr
    return out


@pytest.mark.parametrize("name, version", [
    *[(name, version) for name in ("reference_results", "replay_file", "audit_file", "simulate_file")
      for version in VERSIONS],
    *[("analysis_file", version) for version in VERSIONS],
])
def test_no_high_priority_cf_finding(request, name, version, tmp_path):
    path = request.getfixturevalue(name)
    findings = [f for f in high_priority_findings(path, version, tmp_path) if not f.endswith(ELAPSED_TIME_FINDING)]
    assert not findings, f"{path.name} ({version}):\n" + "\n".join(findings)


def test_every_numeric_variable_has_units_and_every_file_says_what_it_is(reference_results, replay_file,
                                                                         simulate_file, analysis_file, audit_file):
    import netCDF4

    for path in (analysis_file, audit_file):  # every data file declares the one CF version
        with netCDF4.Dataset(path) as nc:
            assert nc.Conventions == CONVENTIONS and nc.title and nc.history, path
    for path in (reference_results, replay_file, simulate_file):
        with netCDF4.Dataset(path) as nc:
            assert nc.Conventions == CONVENTIONS and nc.title and nc.history, path
            for name, variable in nc.variables.items():
                numeric = variable.dtype != str and np.dtype(variable.dtype).kind in "fiu"
                if numeric and "flag_values" not in variable.ncattrs() and name != "final_state":
                    assert "units" in variable.ncattrs(), (path.name, name)
                if name in nc.dimensions:
                    assert "_FillValue" not in variable.ncattrs(), (path.name, name)


def test_units_parse_and_gain_margins_are_ratios(tmp_path):
    """Every unit of a results.nc parses with UDUNITS (cf-units); a gain margin's unit is "1" (a ratio), never
    "dB", which unit libraries read as a power ratio (23.54 dB became 226 instead of 15.03)."""
    import cf_units

    from campaigns.bench.adapter import margin_variables

    class _Spec:  # the two fields margin_variables reads
        datasets = [object()]
        runs_per_dataset = 1

    variables = margin_variables(_Spec(), lambda d, i: None,
                                 map_chunks=lambda f, chunks: [[({"speed_loop_gain_margin": 23.54}, "")]])
    values, attrs = variables["speed_loop_gain_margin"][1:]
    assert attrs["units"] == "1" and values[0, 0] == pytest.approx(15.03, abs=0.01)
    for _, _, attrs in variables.values():
        if "units" in attrs:
            cf_units.Unit(attrs["units"])  # raises on a unit UDUNITS does not know


@pytest.mark.parametrize("name", ["simulate_file", "replay_file"])
def test_a_run_reads_back_in_seconds_from_the_start_of_its_test(request, name):
    """``xr.open_dataset("ds2.nc").motor_current.plot()`` plots against seconds, not dates of 1970 (issue 39): the
    run's time is stored in units ``s`` without a reference date, and read back as the float seconds it was."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = request.getfixturevalue(name)
    with xr.open_dataset(path) as ds:
        time = ds["time"]
        assert time.dtype == np.float64 and time.attrs["units"] == "s" and "since" not in time.attrs["units"]
        if name == "simulate_file":  # a replay keeps its run function's words (here the synthetic model's)
            assert time.attrs["long_name"] == "time since the start of the test procedure"
        assert float(time[0]) == 0.0 and np.all(np.diff(time.values) > 0)
        signal = next(v for v in ("motor_current", "nut1_position") if v in ds)
        line = ds[signal].plot()[0]
        np.testing.assert_array_equal(line.get_xdata(), time.values)
        plt.close("all")
