"""A campaign accepted is never lost: kill -9 of the server mid-campaign, restart, and it finishes exactly once."""

from __future__ import annotations

import psutil
import xarray as xr
from service_helpers import Server, chunk_runs, client, create_token, submit, wait_final, wait_until

RUNS = 6  # per data set; 12 runs of one-run chunks on one worker: several seconds of runs to kill into


def test_kill_9_mid_campaign_then_restart_finishes_with_nothing_lost_or_duplicated(tmp_path):
    data = tmp_path / "data"
    token = create_token(data, "submitter", "submit")
    server = Server(data, tmp_path / "server.log").start()
    try:
        api = client(server, token)
        record = submit(api, RUNS)
        campaign_id, total = record["id"], record["progress"]["runs_total"]
        out = data / "campaigns" / campaign_id / "out"
        wait_until(lambda: len(chunk_runs(out)) >= 2, what="two recorded runs")
        server.kill9()
    finally:
        server.stop()
    recorded_before = chunk_runs(out)
    assert 0 < len(recorded_before) < total, "the kill did not land mid-campaign"
    assert not (out / "results.nc").exists()

    server = Server(data, tmp_path / "server-restarted.log").start()
    try:
        api = client(server, token)
        record = wait_final(api, campaign_id)
    finally:
        server.stop()
    assert record["state"] == "done", record["error"]
    assert record["legs"] == 2
    assert record["progress"]["runs_done"] == total
    recorded = chunk_runs(out)
    assert len(recorded) == len(set(recorded)) == total, "a run recorded twice, or one missing"
    assert set(recorded_before) <= set(recorded)
    with xr.open_dataset(out / "results.nc") as results:
        assert results.attrs["execution_executed_runs"] == total - len(recorded_before)  # only the missing ones
        assert (results["status"].values != "").all()
        assert results.sizes["run"] == RUNS and results.sizes["dataset"] == 2
    assert (out / "report.html").exists() and (out / "analysis.nc").exists()


def test_a_runner_outliving_a_killed_server_is_waited_for_not_doubled(tmp_path):
    """kill -9 of the server process alone: its runner goes on; the restarted server waits for it (one leg)."""
    data = tmp_path / "data"
    token = create_token(data, "submitter", "submit")
    server = Server(data, tmp_path / "server.log").start()
    try:
        api = client(server, token)
        campaign_id = submit(api, 2)["id"]
        wait_until(lambda: api.get(f"/api/v1/campaigns/{campaign_id}").json()["legs"] == 1, what="the runner's start")
        runner_tree = server.tree()[1:]
        server.process.kill()
        server.process.wait()
        restarted = Server(data, tmp_path / "server-restarted.log").start()
        try:
            record = wait_final(client(restarted, token), campaign_id)
        finally:
            restarted.stop()
    finally:
        server.stop()
        for process in runner_tree:  # nothing is left behind by the test, whatever happened
            try:
                process.kill()
            except psutil.NoSuchProcess:
                pass
    assert record["state"] == "done", record["error"]
    assert record["legs"] == 1  # the orphan finished the campaign; no second runner was started
    recorded = chunk_runs(data / "campaigns" / campaign_id / "out")
    assert len(recorded) == len(set(recorded)) == record["progress"]["runs_total"]
