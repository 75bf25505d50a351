"""Resume after the driver is SIGKILLed; refusal to mix results."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from campaign_helpers import SYNTHETIC_SPEC, data_variables, load, write_spec

import campaigns
from campaigns.runner.synthetic import SyntheticModel, synthetic_run

# Every run of data sets ds6 and ds5 hangs (far past the 600 s budget): the driver can finish ds2 and ds4
# but never the campaign, so it is always killed mid-way, however fast or slow the machine is.
DRIVER = """
import campaigns
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, SyntheticModel
hangs = {{(d, i): "hang" for d in ("ds6", "ds5") for i in range(40)}}
campaigns.run_campaign({spec!r}, {out!r}, workers=2, progress=False, catalog=SYNTHETIC_CATALOG,
                       run_function=SyntheticModel(faults=hangs, log_dir={log!r}))
"""


def _runs_logged(log_dir: Path) -> int:
    return sum(len(p.read_text().splitlines()) for p in log_dir.glob("runs-*.log"))


def test_resume_after_sigkill_reruns_only_unfinished_chunks(reference_results, tmp_path):
    # small chunks: several exist when killed
    spec_path = write_spec(tmp_path, "[execution]\nchunk_size = 5\ntimeout = 600.0\n")
    out, log_before, log_after = tmp_path / "out", tmp_path / "log1", tmp_path / "log2"
    log_before.mkdir()
    log_after.mkdir()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    code = DRIVER.format(spec=str(spec_path), out=str(out), log=str(log_before))
    driver = subprocess.Popen([sys.executable, "-c", code], env=env, start_new_session=True)
    try:
        deadline = time.monotonic() + 300  # generous: only a broken driver takes this long to write 6 chunks
        while len(list(out.glob("chunks/*/d*.npz"))) < 6:
            assert driver.poll() is None, "driver ended before it could be killed"
            assert time.monotonic() < deadline, "no chunks written"
            time.sleep(0.05)
    finally:
        os.killpg(driver.pid, signal.SIGKILL)  # the driver, its workers and their sandboxes
        driver.wait()
    assert not (out / "results.nc").exists()
    before = {p: p.stat().st_mtime_ns for p in out.glob("chunks/*/d*.npz")}
    finished = sum(len(np.load(p)["run"]) for p in before)
    assert 30 <= finished <= 80  # at least the 6 chunks waited for, at most ds2 and ds4

    spec = load(spec_path)
    path = campaigns.run_campaign(spec, out, workers=2, resume=True, progress=False,
                                  run_function=SyntheticModel(log_dir=str(log_after)))

    assert {p: p.stat().st_mtime_ns for p in before} == before  # finished chunks untouched
    assert _runs_logged(log_after) == 160 - finished  # only the unfinished runs executed
    with xr.open_dataset(path) as resumed, xr.open_dataset(reference_results) as reference:
        xr.testing.assert_identical(data_variables(resumed), data_variables(reference))


def test_output_directory_of_another_spec_is_refused(reference_results, tmp_path):
    out = reference_results.parent
    other = load(SYNTHETIC_SPEC, runs=7)
    with pytest.raises(campaigns.CampaignError, match="different spec.*runs_per_dataset"):
        campaigns.run_campaign(other, out, resume=True, progress=False, run_function=synthetic_run)
    with pytest.raises(campaigns.CampaignError, match="resume=True"):
        campaigns.run_campaign(load(SYNTHETIC_SPEC), out, progress=False, run_function=synthetic_run)


def test_resume_of_a_finished_campaign_runs_nothing(reference_results, tmp_path):
    log = tmp_path / "log"
    log.mkdir()
    spec = load(SYNTHETIC_SPEC)
    path = campaigns.run_campaign(spec, reference_results.parent, resume=True, progress=False,
                                  run_function=SyntheticModel(log_dir=str(log)))
    assert _runs_logged(log) == 0
    assert path == reference_results
