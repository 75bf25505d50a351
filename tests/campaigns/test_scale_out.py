"""Scale-out: a real ``dask scheduler`` and two ``dask worker`` processes on the loopback interface.

The thesis campaign (two runs per data set, so every data set takes part, and the fidelity audit of the data sets
its automatic choice simplifies) is run
through ``twin campaign run --scheduler`` against that cluster and through the library on a local
cluster; the stored results must be identical, whatever executed them (README: "Pointing a campaign
at your own cluster"). Both campaigns take about a minute of CPU on a loaded 2-core machine.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
import xarray as xr
from campaign_helpers import data_variables

import campaigns

THESIS_SPEC = Path(campaigns.__file__).parent / "specs" / "thesis_backlash.toml"
RUNS = 2
START_TIMEOUT = 120.0  # s: a scheduler and two workers import dask and the twin on a loaded machine


def _dask(*args: str, log: Path) -> subprocess.Popen:
    """A ``dask`` command-line process of this interpreter's environment, its output in ``log``."""
    with log.open("w") as handle:  # the child keeps its own descriptor
        return subprocess.Popen([sys.executable, "-m", "dask", *args], stdout=handle, stderr=subprocess.STDOUT,
                                env=dict(os.environ), start_new_session=True)


def _wait_for(condition, what: str, logs: list[Path]) -> None:
    deadline = time.monotonic() + START_TIMEOUT
    while not condition():
        if time.monotonic() > deadline:
            pytest.fail(f"{what} within {START_TIMEOUT:g} s; logs:\n" + "\n".join(p.read_text() for p in logs))
        time.sleep(0.5)


@pytest.fixture
def loopback_cluster(tmp_path):
    """Address of a scheduler on 127.0.0.1 with two single-threaded worker processes; torn down after."""
    scheduler_file = tmp_path / "scheduler.json"
    logs = [tmp_path / "scheduler.log", tmp_path / "worker1.log", tmp_path / "worker2.log"]
    processes = [_dask("scheduler", "--host", "127.0.0.1", "--port", "0", "--dashboard-address", ":0",
                       "--scheduler-file", str(scheduler_file), log=logs[0])]
    try:
        _wait_for(scheduler_file.exists, "the scheduler did not write its address", logs)
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        for log in logs[1:]:
            processes.append(_dask("worker", address, "--nthreads", "1", "--nworkers", "1", "--host", "127.0.0.1",
                                   "--dashboard-address", ":0", "--no-nanny", log=log))
        from distributed import Client

        with Client(address, timeout=START_TIMEOUT) as client:
            _wait_for(lambda: len(client.scheduler_info()["workers"]) == 2, "two workers did not register", logs)
        yield address
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in reversed(processes):
            try:
                process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


def test_thesis_campaign_on_a_loopback_cluster_matches_the_local_cluster(loopback_cluster, tmp_path):
    twin_command = Path(sys.executable).with_name("twin")
    remote_out = tmp_path / "remote"
    completed = subprocess.run([str(twin_command), "campaign", "run", str(THESIS_SPEC), "--runs", str(RUNS),
                                "--out", str(remote_out), "--scheduler", loopback_cluster],
                               capture_output=True, text=True, timeout=1800)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    local = campaigns.run_campaign(campaigns.load_spec(THESIS_SPEC, runs=RUNS), tmp_path / "local", workers=2,
                                   progress=False)
    with xr.open_dataset(remote_out / "results.nc") as remote_ds, xr.open_dataset(local) as local_ds:
        assert remote_ds.attrs["execution_workers"] == loopback_cluster
        assert remote_ds.sizes["dataset"] == 7 and remote_ds.sizes["run"] == RUNS
        assert (local_ds["status"] == "ok").all()
        # the fidelity audit ran on the remote cluster too, with the same verdict
        assert remote_ds.attrs["fidelity_audit"] == local_ds.attrs["fidelity_audit"]
        xr.testing.assert_identical(data_variables(remote_ds), data_variables(local_ds))
