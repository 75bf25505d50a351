"""Issue 30, point 2: design A against design B, paired where the seeds allow, with known answers."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from app.cli import main
from campaigns.workflows.design_comparison import Shift, compare, describe_shift, failure_text, pairing, spec_changes

RUNS = 40
NAMES = ["d0", "d1"]


def _results(*, seed=7, shift=0.0, scale=1.0, changed_sigma=1.0, other_draws=None, name="A", status=None,
             fixed=None) -> xr.Dataset:
    """Two data sets; the feature is 1 µm times a shared tolerance ``shared`` plus the design's tolerance
    ``design`` (whose sigma is the design change), shifted by ``shift`` and scaled by ``scale``."""
    rng = np.random.default_rng(0)  # the runs' draws: the same for both designs (common random numbers)
    shared = rng.normal(0, 1, (2, RUNS))
    unit_design = rng.normal(0, 1, (2, RUNS))
    shared = shared if other_draws is None else other_draws
    design = changed_sigma * unit_design
    feature = 1e-6 * scale * (shared + 0.1 * design) + shift
    datasets = [{"name": n, **({"parameters": fixed[n]} if fixed and n in fixed else {})} for n in NAMES]
    spec = {"spec": {"name": name, "root_seed": seed, "datasets": datasets, "base": {"parameters": "bench"},
                     "observability": {"sweep": []}},
            "resolved": [{"target": "t.shared", "kind": "gaussian", "sigma": 1.0},
                         {"target": "t.design", "kind": "gaussian", "sigma": changed_sigma}]}
    return xr.Dataset(
        {"f": (("dataset", "run"), feature, {"units": "m", "role": "feature"}),
         "t.shared": (("dataset", "run"), shared, {"units": "1", "role": "sampled"}),
         "t.design": (("dataset", "run"), design, {"units": "1", "role": "sampled"}),
         "status": (("dataset", "run"), np.full((2, RUNS), "ok", dtype=object) if status is None else status)},
        coords={"dataset": NAMES, "run": np.arange(RUNS)}, attrs={"spec_json": json.dumps(spec), "spec_hash": name})


def test_common_random_numbers_are_detected_and_a_known_shift_is_recovered():
    a = _results()
    b = _results(shift=0.3e-6, changed_sigma=0.5, name="B")
    paired, why, changed = pairing(a, b)
    assert paired and changed == ["t.design"]
    assert why.startswith("same root seed 7, same data sets; 1 tolerances bit-identical run by run, 1 drawn from "
                          "another distribution")
    found = compare(a, b)
    for shift in (s for s in found.shifts if s.feature == "f"):
        # paired: the shared tolerance cancels, the shift is resolved within its interval
        assert shift.mean.lower < 0.3e-6 < shift.mean.upper and shift.mean.resolved
        assert shift.mean.upper - shift.mean.lower < 0.1e-6  # far tighter than the 1 µm spread: the pairing pays
    assert found.sentence.startswith("B against A (paired run by run): no analyses to compare verdicts; the largest "
                                     "resolved change is f")


def test_other_seeds_or_draws_are_compared_unpaired_and_say_why():
    a = _results()
    found = compare(a, _results(seed=8, shift=0.3e-6, name="B"))
    assert not found.paired and found.pairing.startswith("different root seeds (7 and 8)")
    shifted = _results(other_draws=np.random.default_rng(5).normal(0, 1, (2, RUNS)), name="B")
    paired, why, _ = pairing(a, shifted)
    assert not paired and "1 unchanged tolerance(s) drew other values (t.shared)" in why
    same = compare(a, _results(name="B"))
    assert all(not s.mean.resolved for s in same.shifts)
    assert "no shift of any feature's mean is resolved" in same.sentence


def test_a_changed_spread_is_resolved_by_the_sd_shift():
    found = compare(_results(), _results(scale=2.0, name="B"))
    for shift in found.shifts:
        assert shift.sd.lower > 0 and shift.sd.resolved


def _analysis(verdict: str, name: str) -> xr.Dataset:
    return xr.Dataset({"requirement_verdict": ("feature", np.array([verdict], dtype=object)),
                       "requirement_statement": ("feature", np.array([f"{verdict}: of {name}"], dtype=object))},
                      coords={"feature": ["f"]}, attrs={"source_spec_hash": name})


def test_verdict_changes_lead_the_sentence_and_the_cli_prints_them(tmp_path, capsys):
    a, b = _results(), _results(shift=0.3e-6, changed_sigma=0.5, name="B")
    found = compare(a, b, _analysis("undetermined", "A"), _analysis("met", "B"))
    [change] = found.verdicts
    assert change.changed and found.sentence == (
        "B against A (paired run by run): 1 verdict(s) change: f: minimum detectable fault size against the "
        "requirement: undetermined in A, met in B.")
    for campaign, results, verdict in (("a", a, "undetermined"), ("b", b, "met")):
        (tmp_path / campaign).mkdir()
        results.to_netcdf(tmp_path / campaign / "results.nc")
        _analysis(verdict, campaign.upper()).to_netcdf(tmp_path / campaign / "analysis.nc")
    assert main(["campaign", "compare", str(tmp_path / "b" / "results.nc"), str(tmp_path / "a" / "results.nc")]) == 0
    out = capsys.readouterr().out
    assert "pairing: paired: same root seed 7" in out
    assert "CHANGED" in out and out.strip().endswith("undetermined in A, met in B.")


@pytest.mark.parametrize("runs_b", [RUNS, RUNS - 10])
def test_the_first_runs_are_paired_when_one_campaign_has_more(runs_b):
    a, b = _results(), _results(shift=0.3e-6, name="B").isel(run=slice(0, runs_b))
    found = compare(a, b)
    assert found.paired and all(s.n_a == s.n_b == runs_b for s in found.shifts)


@pytest.mark.parametrize(("shift", "text"), [
    # a sub-nanometre shift of a micrometre feature: in nm, never "0.000557 µm"
    (Shift(5.57e-10, -7.34e-10, 1.84e-9), "+0.6 nm (95 % interval -0.7 … 1.8 nm)"),
    # rounded at the second digit of the half-width (0.25 µm): 1.23, not 1.234
    (Shift(1.234e-6, 1.0e-6, 1.5e-6), "+1.23 µm (95 % interval 1.00 … 1.50 µm)"),
    # a half-width of 300 nm: rounded to tens of nm
    (Shift(-3.7e-8, -3.4e-7, 2.66e-7), "-40 nm (95 % interval -340 … 270 nm)"),
    # an interval far narrower than the value: 3 significant digits, not the round-off's
    (Shift(3.0e-10, 3.0e-10 - 1e-22, 3.0e-10 + 1e-22), "+300 pm (95 % interval 300 … 300 pm)"),
    # identical runs in both designs (round-off below 1e-15 m)
    (Shift(1e-21, -1e-21, 2e-21), "0 (95 % interval 0 … 0: identical in every run)"),
])
def test_a_shift_reads_in_the_unit_and_to_the_precision_its_interval_resolves(shift, text):
    assert describe_shift(shift, "m") == text


PULSES = "sensors.torque_meter_encoder_pulses_per_turn"


def test_a_parameter_a_data_set_fixes_is_named_with_both_values(tmp_path, capsys):
    """Issue 39: design B sets the torque meter's encoder to 5000 pulses per turn in [datasets.parameters]; compare
    said "0 changed by the design" and named nothing. The value A leaves out is the bench parameter set's 2000."""
    a, b = _results(), _results(name="B", fixed={"d1": {PULSES: 5000}})
    found = compare(a, b)  # the library reads no parameter set (the reports import it): the CLI gives the value
    assert found.spec_changes == [f"datasets[d1].parameters.{PULSES}: the parameter set's nominal → 5000"]
    assert found.design_changes == [PULSES] and found.paired
    assert found.pairing.endswith("0 drawn from another distribution, 1 parameter(s) a data set fixes otherwise")
    for campaign, results in (("a", a), ("b", b)):
        (tmp_path / campaign).mkdir()
        results.to_netcdf(tmp_path / campaign / "results.nc")
    assert main(["campaign", "compare", str(tmp_path / "b" / "results.nc"), str(tmp_path / "a" / "results.nc")]) == 0
    assert f"  datasets[d1].parameters.{PULSES}: 2000 (nominal) → 5000\n" in capsys.readouterr().out


def test_every_spec_difference_is_one_line_by_data_set_and_by_target():
    a = {"name": "A", "description": "x", "root_seed": 7, "runs_per_dataset": 40, "base": {"parameters": "nope"},
         "datasets": [{"name": "d0", "conditions": {"backlash": 8e-05}}, {"name": "d1"}],
         "uncertainties": [{"target": "t.a", "half_range": 10.0}, {"target": "t.b", "unit": "um"}]}
    b = {"name": "B", "description": "y", "root_seed": 7, "runs_per_dataset": 20, "base": {"parameters": "nope"},
         "datasets": [{"name": "d0", "conditions": {"backlash": 4e-05}, "parameters": {"p.q": 3.0}},
                      {"name": "d2"}],
         "uncertainties": [{"target": "t.b", "unit": "mm"}, {"target": "t.a", "half_range": 5.0}]}
    assert spec_changes(a, b) == [
        "datasets[d0].conditions.backlash: 8e-05 → 4e-05",
        "datasets[d0].parameters.p.q: the parameter set's nominal → 3",
        "datasets[d1]: only in A",
        "datasets[d2]: only in B",
        "runs_per_dataset: 40 → 20",
        "uncertainties[t.a].half_range: 10 → 5",  # by target, whatever the rows' order
        "uncertainties[t.b].unit: 'um' → 'mm'",
    ]
    assert spec_changes(a, a) == []
    assert spec_changes(a, b, nominal=lambda parameters, target: f"{parameters} {target}")[1] == (
        "datasets[d0].parameters.p.q: nope p.q → 3")


def test_failed_runs_are_counted_and_comparisons_without_an_interval_are_not_counted_as_unresolved():
    """Issue 39: with whole data sets timed out, compare said "no shift of any feature's mean is resolved (95 %
    intervals include 0)" although those data sets had no interval."""
    status = np.full((2, RUNS), "ok", dtype=object)
    status[1, :] = "timeout"
    status[0, :3] = "diverged"
    found = compare(_results(), _results(name="B", status=status))
    [made, unmade] = found.shifts
    assert made.made and not unmade.made and (made.n_a, made.n_b, unmade.n_b) == (RUNS - 3, RUNS - 3, 0)
    assert found.failed_b == {"d0": 3, "d1": RUNS} and found.failed_a == {"d0": 0, "d1": 0}
    assert found.sentence == (
        "B against A (paired run by run): no analyses to compare verdicts; no shift of any feature's mean is resolved "
        "among the 1 comparisons made (95 % intervals include 0); 1 of 2 comparisons could not be made (fewer than 3 "
        "pairs ok in both with a finite feature: d1); runs that did not end ok: 43 of 80 in B, none in A.")
    assert failure_text(found, detail=True) == (
        "runs that did not end ok: 43 of 80 in B (diverged 3, timeout 40; d0 3 of 40, d1 40 of 40); none in A")
    nothing = np.full((2, RUNS), "timeout", dtype=object)
    found = compare(_results(), _results(name="B", status=nothing))
    assert "no shift" not in found.sentence and "2 of 2 comparisons could not be made" in found.sentence


def test_a_truncated_analysis_beside_good_results_is_one_line(tmp_path, capsys):
    for campaign, results in (("a", _results()), ("b", _results(name="B"))):
        (tmp_path / campaign).mkdir()
        results.to_netcdf(tmp_path / campaign / "results.nc")
    analysis = tmp_path / "b" / "analysis.nc"
    _analysis("met", "B").to_netcdf(analysis, engine="netcdf4")
    whole = analysis.read_bytes()
    analysis.write_bytes(whole[: len(whole) // 2])
    assert main(["campaign", "compare", str(tmp_path / "b" / "results.nc"), str(tmp_path / "a" / "results.nc")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"{tmp_path / 'b' / 'analysis.nc'}: cannot be read" in err
    assert f"`twin campaign analyze {tmp_path / 'b' / 'results.nc'} --force` writes it again" in err
