"""Issue 17, row by row: campaigns that cannot lose, mix or misreport data.

Each test replays one row of the issue's table (what a careless or unlucky user tried) and checks
the behaviour now promised in docs/campaigns.md, "What BenchTwin guarantees".
"""

from __future__ import annotations

import errno
import json
import logging
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from campaign_helpers import SYNTHETIC_SPEC, data_variables, load, write_spec

import campaigns
from app.cli import main
from campaigns.bench.replay import replay_run
from campaigns.runner import budget, execution
from campaigns.runner.runs import execute, kill_grace, run_function_name
from campaigns.runner.sampling import sample
from campaigns.runner.sandbox import Sandbox
from campaigns.runner.spec import MAX_RUNS_PER_DATASET, SpecError
from campaigns.runner.storage import CampaignError, OutputLock, atomic_write, load_chunk
from campaigns.runner.synthetic import SyntheticModel, synthetic_run

SPECS = Path(campaigns.__file__).parent / "specs"


def _runs_logged(log_dir: Path) -> int:
    return sum(len(p.read_text().splitlines()) for p in log_dir.glob("runs-*.log"))


def _copy_results(reference_results: Path, tmp_path: Path) -> Path:
    copy = tmp_path / "results.nc"
    shutil.copyfile(reference_results, copy)
    return copy


# --- Row 1: `twin campaign analyze R.nc --out R.nc` overwrote the results --------------------------

def test_analyze_refuses_to_overwrite_its_input_or_an_existing_output(reference_results, tmp_path, capsys):
    results = _copy_results(reference_results, tmp_path)
    before = results.read_bytes()
    assert main(["campaign", "analyze", str(results), "--out", str(results)]) == 2
    assert "refusing to write the output over its own input" in capsys.readouterr().err
    assert main(["campaign", "analyze", str(results), "--out", str(results), "--force"]) == 2  # never over the input
    assert results.read_bytes() == before
    analysis = tmp_path / "analysis.nc"
    analysis.write_text("an earlier analysis")
    assert main(["campaign", "analyze", str(results)]) == 2
    assert "already exists; pass --force" in capsys.readouterr().err
    assert analysis.read_text() == "an earlier analysis"


def test_report_refuses_to_overwrite_an_existing_report(reference_results, tmp_path, capsys):
    out = tmp_path / "report"
    out.mkdir()
    (out / "report.html").write_text("an earlier report")
    assert main(["report", str(reference_results), "--out", str(out)]) == 2
    assert "report.html already exists; pass --force" in capsys.readouterr().err
    assert (out / "report.html").read_text() == "an earlier report"


# --- Row 2: a 7-run campaign silently replaced a 70-run results.nc without spec.json -------------

@pytest.mark.parametrize("resume", [False, True])
def test_results_without_spec_json_are_refused(reference_results, tmp_path, resume):
    out = tmp_path / "out"
    out.mkdir()
    foreign = _copy_results(reference_results, out)
    before = foreign.read_bytes()
    with pytest.raises(CampaignError, match="no spec.json"):
        campaigns.run_campaign(load(SYNTHETIC_SPEC, runs=7), out, resume=resume, progress=False,
                               run_function=synthetic_run)
    assert foreign.read_bytes() == before and sorted(p.name for p in out.iterdir()) == ["results.nc"]  # lock removed


# --- Row 3: two drivers on one --out both ran and crashed each other -----------------------------

def test_a_second_driver_on_the_same_directory_is_refused_at_once(tmp_path):
    out = tmp_path / "out"
    holder = subprocess.Popen(
        [sys.executable, "-c",
         f"from campaigns.runner.storage import OutputLock; import sys, time; OutputLock({str(out)!r}).acquire(); "
                               "print('locked', flush=True); time.sleep(600)"],
        stdout=subprocess.PIPE, text=True, env=dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p)))
    try:
        assert holder.stdout.readline().strip() == "locked"
        in_flight = out / "chunks" / ".d000-r000000-000004.npz.abc.tmp"  # the first driver's file being written
        in_flight.parent.mkdir(parents=True)
        in_flight.write_text("half written")
        log = tmp_path / "log"
        log.mkdir()
        with pytest.raises(CampaignError, match=rf"in use by another campaign driver \(pid {holder.pid} "):
            campaigns.run_campaign(load(SYNTHETIC_SPEC), out, resume=True, progress=False,
                                   run_function=SyntheticModel(log_dir=str(log)))
        assert in_flight.exists() and not list(log.iterdir())  # nothing of the other driver's touched, nothing run
    finally:
        holder.kill()
        holder.wait()
        holder.stdout.close()
    with OutputLock(out):  # the OS released the dead driver's lock
        pass


def test_the_lock_is_held_for_the_drivers_lifetime(tmp_path):
    out = tmp_path / "out"
    with OutputLock(out):
        with pytest.raises(CampaignError, match="in use by another campaign driver"):
            OutputLock(out).acquire()
    OutputLock(out).acquire().release()


# --- Row 4: a truncated chunk gave a zipfile traceback on resume --------------------------------

def test_corrupt_and_truncated_chunks_are_named_moved_aside_and_rerun(reference_results, tmp_path, caplog):
    spec = load(write_spec(tmp_path, "[execution]\nchunk_size = 10\n"))
    out = tmp_path / "out"
    first = campaigns.run_campaign(spec, out, workers=1, progress=False, run_function=synthetic_run)
    first.unlink()
    chunks = sorted(out.glob("chunks/*/d*.npz"))
    truncated, flipped = chunks[1], chunks[5]
    truncated.write_bytes(truncated.read_bytes()[: truncated.stat().st_size // 2])
    data = bytearray(flipped.read_bytes())
    data[len(data) // 2] ^= 0xFF  # one flipped byte in the middle of an array
    flipped.write_bytes(bytes(data))
    for damaged in (truncated, flipped):
        with pytest.raises(CampaignError, match=f"corrupt chunk {damaged}"):
            load_chunk(damaged)
    log = tmp_path / "log"
    log.mkdir()
    with caplog.at_level(logging.WARNING, logger="campaigns"):
        path = campaigns.run_campaign(spec, out, workers=1, resume=True, progress=False,
                                      run_function=SyntheticModel(log_dir=str(log)))
    assert str(truncated) in caplog.text and str(flipped) in caplog.text and "will run again" in caplog.text
    assert (sorted(p.name.split(".npz")[0] for p in out.glob("corrupt/*/*"))
            == sorted(p.stem for p in (truncated, flipped)))
    assert _runs_logged(log) == 20  # the two chunks' runs, nothing else
    with xr.open_dataset(path) as resumed, xr.open_dataset(reference_results) as reference:
        xr.testing.assert_identical(data_variables(resumed), data_variables(reference))


# --- Row 5: read-only or full --out gave raw OSError tracebacks, a full disk started the cluster ----

def _demo(runs: int = 1) -> list[str]:
    return ["campaign", "run", str(SPECS / "demo.toml"), "--runs", str(runs)]


def test_an_unwritable_output_directory_is_one_clear_message(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a directory")
    assert main([*_demo(), "--out", str(blocker / "out")]) == 2
    err = capsys.readouterr().err
    assert f"cannot use output directory {blocker / 'out'}" in err and "Traceback" not in err


def test_a_read_only_file_system_is_one_clear_message(tmp_path, capsys, monkeypatch):
    def read_only(self, *args, **kwargs):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(self))

    monkeypatch.setattr(Path, "mkdir", read_only)
    assert main([*_demo(), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'out'}" in err and "Read-only file system" in err and "Traceback" not in err


def test_a_full_disk_is_refused_before_the_cluster_starts(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(budget.shutil, "disk_usage", lambda path: shutil._ntuple_diskusage(10**9, 10**9 - 1000, 1000))
    monkeypatch.setattr(execution, "_client", lambda *a, **k: pytest.fail("the cluster must not start"))
    assert main([*_demo(50), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "not enough free disk space (1 kB free" in err and not (tmp_path / "out").exists()


def test_a_write_that_fails_midway_names_the_file_and_leaves_no_temporary(tmp_path):
    def disk_full(tmp):
        tmp.write_text("partial")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    with pytest.raises(CampaignError, match=f"cannot write {tmp_path / 'x.nc'}: No space left on device"):
        atomic_write(tmp_path / "x.nc", disk_full)
    assert list(tmp_path.iterdir()) == []


def test_a_missing_spec_file_is_one_clear_message(tmp_path, capsys):
    assert main(["campaign", "run", str(tmp_path / "nope.toml")]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'nope.toml'}: cannot read the spec: No such file or directory" in err


# --- Row 6: non-UTF-8 bytes or `extends = 5` gave tracebacks -------------------------------------

def test_non_utf8_and_a_wrong_extends_are_spec_errors(tmp_path, capsys):
    latin = tmp_path / "latin.toml"
    latin.write_bytes('name = "caf\u00e9"\n'.encode("latin-1"))
    with pytest.raises(SpecError, match=r"latin.toml: not UTF-8 text \(byte 0xe9 at offset 11\)"):
        load(latin)
    extends = tmp_path / "extends.toml"
    extends.write_text("extends = 5\n")
    with pytest.raises(SpecError, match="extends.toml: extends: must be the path of another spec file .* got 5"):
        load(extends)
    assert main(["campaign", "run", str(latin), "--out", str(tmp_path / "out")]) == 2
    assert "not UTF-8" in capsys.readouterr().err and not (tmp_path / "out").exists()


# --- Row 7: a spec with 8 errors listed 6 --------------------------------------------------------

def test_cross_field_errors_are_listed_whatever_else_is_wrong(tmp_path):
    path = write_spec(tmp_path, """
root_seed = -1
[[datasets]]
name = "ds2"
conditions = { backlash = 80e-6, wind = 1.0 }
[[datasets]]
name = "ds2"
conditions = { backlash = 0.0 }
[observability]
sweep = ["ds2", "nope"]
[[uncertainties]]
target = "synthetic.no_such_parameter"
distribution = "gaussian"
sigma = -0.1
[[uncertainties]]
target = "synthetic.offset"
distribution = "uniform"
low = 2.0
high = 1.0
unit = "um"
[execution]
timeout = 0.0
""")
    with pytest.raises(SpecError) as info:
        load(path)
    problems = info.value.problems
    expected = ["root_seed:", "datasets[0].conditions.wind: unknown condition", "execution.timeout:",
                "uncertainties[0].sigma:", "uncertainties[0]: unknown parameter 'synthetic.no_such_parameter'",
                "uncertainties[1]: low (2) > high (1)", "datasets: duplicate name(s) ds2",
                "observability.sweep: unknown data set(s) nope"]
    for prefix in expected:
        assert any(p.startswith(prefix) for p in problems), f"{prefix!r} not in {problems}"
    assert len(problems) == len(expected), problems


# --- Row 8: runs = 200000 was accepted, then a killed start-up blocked the directory ----------------

def test_runs_have_an_upper_bound(tmp_path):
    with pytest.raises(SpecError,
                       match=rf"runs_per_dataset: 200000 is outside the allowed range \[1, {MAX_RUNS_PER_DATASET}\]"):
        load(SYNTHETIC_SPEC, runs=200_000)


def test_a_directory_with_a_spec_but_no_results_is_not_refused(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "spec.json").write_text(json.dumps({"hash": "0" * 64, "canonical": {}}))  # a driver killed while sampling
    path = campaigns.run_campaign(load(SYNTHETIC_SPEC, runs=2), out, workers=1, progress=False,
                                  run_function=synthetic_run)
    with xr.open_dataset(path) as ds:
        assert (ds["status"] == "ok").all()


def test_the_cost_is_estimated_and_printed_before_the_campaign(capsys, monkeypatch, tmp_path):
    spec = campaigns.load_spec(SPECS / "thesis_backlash.toml")
    from campaigns.bench.adapter import simulate_run

    cost = budget.estimate(spec, simulate_run, workers=2)
    assert cost.runs == 7000 and cost.wall_seconds == pytest.approx(7000 * simulate_run.typical_run_seconds / 2)
    assert cost.disk_bytes >= 2 * 7000 * 8 * (38 + 2)  # every sampled value and feature, in chunks and results.nc
    monkeypatch.setattr(campaigns, "run_campaign", lambda *a, **k: tmp_path / "results.nc")
    assert main(["campaign", "run", str(SPECS / "thesis_backlash.toml"), "--out", str(tmp_path)]) == 0
    # the budget's one estimate, printed as it stands: 7000 runs at the lane engine's ~0.2 s a run on 2 workers
    assert f"campaign thesis_backlash: {cost.describe()}\n" in capsys.readouterr().out
    assert cost.describe().startswith("7000 run(s), about 12 min on 2 worker(s), about ")


# --- Row 9: timeouts charged start-up to runs; the bench ignored the budget without isolation -------

class _SlowStart:
    """A run function whose warm-up takes 3 s and whose run is instant."""

    def warm_up(self, request):
        time.sleep(3.0)

    def __call__(self, request):
        return {"status": "ok", "t_reached": 1.0, "features": {f: 0.0 for f in request.features}}


def _request(tmp_path, timeout: float):
    spec = load(write_spec(tmp_path, f"runs_per_dataset = 1\n[execution]\ntimeout = {timeout}\n"))
    return execution.build_request(spec, sample(spec), 0, 0)


def test_start_up_is_not_charged_to_the_run(tmp_path):
    request = _request(tmp_path, 1.0)  # a 3 s warm-up against a 1 s budget
    sandbox = Sandbox()
    try:
        isolated = sandbox.run(_SlowStart(), request)
    finally:
        sandbox.close()
    assert isolated["status"] == "ok", isolated["failure_reason"]
    assert execute(_SlowStart(), request)["status"] == "ok"  # in-process too


def test_a_run_over_budget_is_a_timeout_without_isolation_too(tmp_path):
    request = _request(tmp_path, 0.1)
    record = execute(SyntheticModel(delay=1.5), request)  # sleeps at least 1.5 s: over its 0.1 s budget + 1 s grace
    assert record["status"] == "timeout" and "over its 0.1 s budget + 1 s grace" in record["failure_reason"]
    assert np.isnan(record["features"]["backlash_feature"])  # a timeout never enters the statistics


def test_the_kill_grace_scales_with_the_budget():
    assert kill_grace(0.5) == 1.0 and kill_grace(600.0) == 60.0


def test_the_cli_accepts_a_timeout(tmp_path):
    assert campaigns.load_spec(SPECS / "demo.toml", timeout=2.5).execution.timeout == 2.5
    with pytest.raises(SpecError, match="execution.timeout"):
        campaigns.load_spec(SPECS / "demo.toml", timeout=-1.0)


# --- Row 10: no way to replay one run -------------------------------------------------------------

@pytest.mark.parametrize("fixture", ["reference_results", "single_worker_results"])
def test_replay_reproduces_stored_runs_bit_identically(fixture, request, tmp_path):
    results = request.getfixturevalue(fixture)
    with xr.open_dataset(results) as stored:
        stored.load()
    for dataset, run in (("ds2", 0), ("ds4", 39), ("ds6", 17), ("ds5", 3)):
        replayed = replay_run(results, dataset, run, out=tmp_path / f"{fixture}-{dataset}-{run}.nc")
        for feature in ("backlash_feature", "backlash_feature_true"):
            value = stored[feature].sel(dataset=dataset, run=run).values
            assert replayed[feature].values.tobytes() == value.tobytes()
            assert replayed.attrs[f"identical_{feature}"] == "yes"
        parameters = json.loads(replayed.attrs["parameters"])
        assert parameters["synthetic.gain"] == float(stored["synthetic.gain"].sel(dataset=dataset, run=run))
        assert replayed.sizes["time"] == 11 and "nut1_position" in replayed  # the full series of the run
        if run < 2:  # a traced run: the stored (decimated) trace is the replayed one
            np.testing.assert_array_equal(stored["trace_nut1_position"].sel(dataset=dataset, trace_run=run),
                                          replayed["nut1_position"])


def test_replay_cli_and_its_refusals(reference_results, tmp_path, capsys):
    out = tmp_path / "run.nc"
    assert main(["campaign", "replay", str(reference_results), "--dataset", "ds6", "--run", "17", "--out",
                 str(out)]) == 0
    printed = capsys.readouterr().out
    assert "backlash_feature: replayed" in printed and "bit-identical" in printed and "DIFFERENT" not in printed
    assert main(["campaign", "replay", str(reference_results), "--dataset", "ds6", "--run", "17", "--out",
                 str(out)]) == 2
    assert main(["campaign", "replay", str(reference_results), "--dataset", "ds9", "--run", "0"]) == 2
    assert "no data set 'ds9'; it has ds2, ds4, ds6, ds5" in capsys.readouterr().err
    assert main(["campaign", "replay", str(reference_results), "--dataset", "ds2", "--run", "40"]) == 2
    assert "runs are 0..39" in capsys.readouterr().err


def test_the_run_function_is_recorded(reference_results):
    with xr.open_dataset(reference_results) as ds:
        assert (
            ds.attrs["run_function"] == "campaigns.runner.synthetic:synthetic_run" == run_function_name(synthetic_run)
        )


# --- Row 11: resuming after an upgrade mixed versions silently ------------------------------------

def test_resume_refuses_to_mix_versions_unless_told(reference_results, tmp_path, monkeypatch):
    spec = load(SYNTHETIC_SPEC)
    out = tmp_path / "out"
    campaigns.run_campaign(spec, out, workers=1, progress=False, run_function=synthetic_run).unlink()
    for chunk in sorted(out.glob("chunks/*/d003-*.npz")):
        chunk.unlink()  # data set ds5 unfinished
    real = execution.provenance
    monkeypatch.setattr(execution, "provenance", lambda fn: {**real(fn), "numpy": "99.0", "model_code": "f" * 64})
    with pytest.raises(CampaignError) as info:
        campaigns.run_campaign(spec, out, resume=True, workers=1, progress=False, run_function=synthetic_run)
    message = str(info.value)
    assert "computed by another version" in message and "-> 99.0" in message and "model code hash" in message
    assert "--allow-version-mix" in message
    path = campaigns.run_campaign(spec, out, resume=True, workers=1, progress=False, run_function=synthetic_run,
                                  allow_version_mix=True)
    with xr.open_dataset(path) as ds:
        assert ds.attrs["version_mix"].startswith("MIXED") and "-> 99.0" in ds.attrs["version_mix"]
        assert len(json.loads(ds.attrs["provenance"])) == 2 and ds.attrs["model_code_hash"] == "mixed"


def test_results_record_versions_and_the_model_code_hash(reference_results):
    with xr.open_dataset(reference_results) as ds:
        assert ds.attrs["benchtwin_version"] and ds.attrs["version_mix"] == "none"
        assert len(ds.attrs["model_code_hash"]) == 64
        assert ds.attrs["model_code_packages"] == "campaigns,sensors,twin"
        record = json.loads(ds.attrs["provenance"])[0]
        assert {"numpy", "numba", "scipy", "benchtwin"} <= set(record)


def test_a_new_spec_file_leaves_the_model_code_hash_and_a_new_model_file_changes_it(tmp_path, monkeypatch):
    """Campaign specs are inputs (keyed by their own spec hash), not the model: adding one beside the shipped specs
    must not make every campaign unresumable; a changed model file must."""
    from campaigns.runner.provenance import code_hash

    package = tmp_path / "hashed_package"
    (package / "specs").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "specs" / "a.toml").write_text("name = 'a'\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    before = code_hash(("hashed_package",))
    code_hash.cache_clear()
    (package / "specs" / "b.toml").write_text("name = 'b'\n")
    assert code_hash(("hashed_package",)) == before
    code_hash.cache_clear()
    (package / "parameters.toml").write_text("x = 1\n")
    assert code_hash(("hashed_package",)) != before
    code_hash.cache_clear()
