"""`twin accuracy` and `twin fidelity audit` end to end, with their printed and stored numbers checked."""

import re
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from scipy.stats import linregress

from app import cli
from campaigns.bench import fidelity_audit
from campaigns.bench.scene_audit import THESIS_SPEC
from campaigns.statistics import accuracy_rule
from campaigns.statistics.accuracy_rule import paired_verdict


def run(*args):
    return subprocess.run([sys.executable, "-m", "app.cli", *args], capture_output=True, text=True, timeout=1200)


def test_accuracy_quick_study(tmp_path):
    """A quick study of 50 ms of ds4: every run ok, RK4's errors fall with the step, the baseline table printed
    is the one stored, and --replot redraws the chart from the stored data."""
    result = run("accuracy", "--quick", "--no-stability", "--scene", "ds4", "--duration", "0.05", "--out",
                 str(tmp_path))
    assert result.returncode == 0, result.stderr
    assert f"wrote work_precision: {tmp_path / 'work_precision.png'}" in result.stdout
    with xr.open_dataset(tmp_path / "work_precision.nc") as study:
        study = study.load()
    assert study.attrs["scene"] == "ds4" and study.attrs["duration"] == 0.05
    off = study.where(study.panel == "quantizers_off", drop=True)
    # the 125 us step is past the explicit methods' stability limits (~4e-5 s): the guard reports it
    for method in ("rk4", "semi_implicit_euler"):
        coarse = off.where((off.method == method) & (off.dt == 1.25e-4), drop=True)
        assert list(coarse.status.values) == ["diverged"], method
    stable = off.where((off.dt < 1e-4) | np.isnan(off.dt), drop=True)
    assert (stable.status == "ok").all()
    # the nut-position error falls at each method's order over the ladder (measured slopes 1.00 and 1.99)
    for method, order in (("semi_implicit_euler", 1.0), ("rosenbrock_w2", 2.0)):
        runs = stable.where(stable.method == method, drop=True)
        slope = linregress(np.log(runs.dt.values), np.log(runs.nut_position_error.values)).slope
        assert slope == pytest.approx(order, abs=0.1), method
    table = pd.read_csv(tmp_path / "control_baseline.csv")
    for row in table.itertuples():
        printed = re.search(re.escape(row.method) + r"\s+(\S+)\s+(\S+)", result.stdout)
        assert printed and float(printed.group(2)) == pytest.approx(row.error, rel=1e-5, abs=1e-300), row.method
    assert table.error.iloc[0] == 0.0 and table.error.iloc[2] < 1e-9  # reference; RK4 on it
    (tmp_path / "work_precision.png").unlink()
    again = run("accuracy", "--replot", "--out", str(tmp_path))
    assert again.returncode == 0 and (tmp_path / "work_precision.png").stat().st_size > 10_000


SHORT_SCENE = 'base = "ds4"\nname = "ds4_short"\nduration = 1.0\n'
#: The thesis study's sampling with only the Eq. 9.12 features: in 1 s the screw moves one way only, so the
#: hysteresis features are undefined (NaN) and a campaign asking for them would record every run as failed.
EQ_9_12_SPEC = f'extends = "{THESIS_SPEC}"\nfeatures = ["backlash_feature", "backlash_feature_true"]\n'


def _paired_verdict(out, feature, tolerance):
    """The audit's verdict of ``feature`` (the accuracy rule's paired part), recomputed from the two results files
    directly over the runs ok in both."""
    with xr.open_dataset(out / "results.nc") as auto, xr.open_dataset(out / "fidelity_audit" / "results.nc") as full:
        auto = auto.isel(run=slice(0, full.sizes["run"]))
        ok = ((auto.status == "ok") & (full.status == "ok")).values.ravel()
        a, f = auto[feature].values.ravel()[ok], full[feature].values.ravel()[ok]
    return paired_verdict(a, f, mean_tolerance=tolerance, min_pairs=fidelity_audit.AUDIT_MIN_PAIRS)


def _audit(tmp_path, runner):
    scene = tmp_path / "short.toml"
    scene.write_text(SHORT_SCENE)
    out = tmp_path / "audit"
    spec = tmp_path / "eq_9_12.toml"
    spec.write_text(EQ_9_12_SPEC)
    return out, runner(["fidelity", "audit", str(scene), "--runs", str(fidelity_audit.AUDIT_MIN_PAIRS),
                        "--workers", "1", "--out", str(out), "--spec", str(spec)])


def test_fidelity_audit_meets_the_tolerance_on_a_scene_file(tmp_path):
    """The fewest sampled runs the audit judges, of a 1 s scene file, auto against full: each feature's printed
    statement is the paired verdict of the stored results, verbatim, and the overall line is the one stored in
    results.nc."""
    out, result = _audit(tmp_path, lambda args: run(*args))
    assert result.returncode == 0, result.stderr
    assert "encoders=" in result.stdout.splitlines()[0]  # the automatic configuration comes first
    for feature in ("backlash_feature", "backlash_feature_true"):
        verdict = _paired_verdict(out, feature, accuracy_rule.MEAN_SHIFT_TOLERANCE)
        assert f"{feature}: {verdict.statement}; max paired" in result.stdout
        # the mean shift is shown within ±0.05 um; the sd ratio of runs that spread by a few hundredths of a um is
        # not always resolved within 10 % from so few pairs (docs/accuracy.md), but never shown outside it
        assert verdict.mean.verdict == "met", f"{feature}: auto shifts the mean on the short ds4 ({verdict})"
        assert verdict.verdict != "not met", f"{feature}: auto differs from full fidelity on the short ds4 ({verdict})"
    with xr.open_dataset(out / "results.nc") as results:
        assert f"fidelity_audit: {results.attrs['fidelity_audit']}" in result.stdout


def test_fidelity_audit_names_what_it_cannot_show_within_the_tolerance(tmp_path, monkeypatch, capsys):
    """Below the measured shift (tolerance 1e-13 m) no feature is met: the overall line names every data
    set/feature with the worst verdict, as recomputed from the stored results, and the CLI still exits 0 (a
    finding, not an error)."""
    tight = accuracy_rule.Tolerance(1e-13, "µm", 1e6, "a tolerance below the measured shift")
    monkeypatch.setitem(accuracy_rule.MEAN_SHIFT_TOLERANCES, "m", tight)  # the table the audit reads by unit
    out, code = _audit(tmp_path, cli.main)
    assert code == 0
    printed = capsys.readouterr().out
    verdicts = {f: _paired_verdict(out, f, 1e-13) for f in ("backlash_feature", "backlash_feature_true")}
    assert all(v.verdict in ("not met", "undetermined") for v in verdicts.values()), verdicts
    worst = "not met" if any(v.verdict == "not met" for v in verdicts.values()) else "undetermined"
    named = ", ".join(f"short/{f}" for f, v in verdicts.items() if v.verdict == worst)
    assert re.search(f"fidelity_audit: {worst}: [^\n]*: {re.escape(named)}\n", printed)
    for feature, verdict in verdicts.items():
        assert f"{feature}: {verdict.statement}; max paired" in printed
