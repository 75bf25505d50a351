"""The report's verdict code on in-memory analyses: page 1 (the executive summary) states each feature's verdict
verbatim with the tone of that verdict, the requirement the analysis states, the runs each data set used, the
failures and the fidelity audit; the influences it lists are the resolved ones. And the input checks of
reports.inputs name what is wrong. No campaign, no PDF: each test runs in milliseconds.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
import xarray as xr

from campaigns.analysis.campaign_analysis import analysis_dataset
from reports import ReportError
from reports.builder import Builder
from reports.inputs import Inputs, load_inputs
from reports.model import Callout, Figure, Paragraph, Table
from reports.sections import executive as executive_section
from reports.units import number

LEVELS = (0.0, 0.5e-6, 2e-6)
NAMES = ("b0", "b1", "b2")
#: Runs per data set: one more than the analysis's detection floor (59), so that the sweeps have a verdict.
RUNS = 60


def results_of(sigma=(0.1e-6, 0.1e-6), *, status=None, gain_effect=0.0, seed=0) -> xr.Dataset:
    """A backlash sweep with a measured feature ``f`` and its true counterpart ``f_true`` (noise ``sigma`` each)."""
    rng = np.random.default_rng(seed)
    gain = rng.uniform(-1, 1, (len(LEVELS), RUNS))
    inert = rng.uniform(-1, 1, (len(LEVELS), RUNS))
    base = np.asarray(LEVELS)[:, None] + gain_effect * gain
    features = {name: base + rng.normal(0, s, base.shape) for name, s in zip(("f", "f_true"), sigma, strict=True)}
    spec = {
        "name": "verdicts",
        "description": "verdict test",
        "base": {"scene": "nominal"},
        "datasets": [{"name": n, "conditions": {"backlash": b}} for n, b in zip(NAMES, LEVELS, strict=True)],
        "observability": {"sweep": list(NAMES)},
    }
    status = np.full(base.shape, "ok", dtype=object) if status is None else status
    for name in features:
        features[name][status != "ok"] = math.nan
    return xr.Dataset(
        {
            **{name: (("dataset", "run"), v, {"role": "feature", "units": "m"}) for name, v in features.items()},
            "p.gain": (("dataset", "run"), gain, {"role": "sampled", "units": "1"}),
            "p.inert": (("dataset", "run"), inert, {"role": "sampled", "units": "1"}),
            "status": (("dataset", "run"), status),
            "failure_reason": (("dataset", "run"), np.where(status == "ok", "", "injected").astype(object)),
            "wall_time": (("dataset", "run"), np.ones(base.shape)),
            "condition_backlash": ("dataset", np.asarray(LEVELS), {"units": "m"}),
        },
        coords={"dataset": list(NAMES), "run": np.arange(RUNS)},
        attrs={"spec_json": json.dumps({"spec": spec}), "spec_hash": "ab" * 32},
    )


def executive(results: xr.Dataset, analysis: xr.Dataset | None = None) -> list:
    """Page 1 of the report of these results (their analysis computed when not given)."""
    if analysis is None:
        analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    inputs = Inputs(results, analysis, None, json.loads(results.attrs["spec_json"]), (), False)
    return list(executive_section.build(Builder(inputs)))


def callouts(items, start: str = "") -> list[Callout]:
    return [c for c in items if isinstance(c, Callout) and c.text.startswith(start)]


@pytest.mark.parametrize(
    ("verdict", "tone", "decision"),
    [("met", "good", "GO"), ("not met", "bad", "NO-GO"), ("undetermined", "info", "UNDETERMINED"),
     ("insufficient data", "muted", "NO DATA")],
)
def test_each_verdict_is_one_decision_line_with_its_own_tone(verdict, tone, decision):
    """The replay of the old bug (a report that said "meets" whatever the analysis found): page 1's line on the
    requirement carries the analysis's verdict as a decision word, with the tone of that verdict; the ideal-sensor
    reading (the true-signal feature) is said on the same line, not as a raw identifier."""
    results = results_of()
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    analysis["requirement_verdict"] = ("feature", np.array([verdict, "met"], dtype=object))
    [line] = callouts(executive(results, analysis), f"{decision} — Detect a 1 µm backlash (Table 9.3) with")
    assert (line.tone, line.link) == (tone, "observability")
    assert line.text.endswith(" With ideal sensors: GO.")
    assert "_true" not in line.text and "f_true" not in " ".join(c.text for c in callouts(executive(results, analysis),
                                                                                          "GO"))


def test_the_computed_verdicts_reach_page_one():
    """Noise 0.1 µm: the 0.5 µm level is detected (met); noise 3 µm on the true signal: never detected (not met)."""
    results = results_of(sigma=(0.1e-6, 3e-6))
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    assert list(analysis["requirement_verdict"].values) == ["met", "not met"]
    [line] = callouts(executive(results, analysis), "GO — Detect a 1 µm backlash")
    upper = float(analysis["minimum_detectable_backlash_ci"].sel(feature="f", bound="upper"))
    assert f"is at most {number(upper * 1e6)} µm (95 % bound), within the requirement" in line.text
    assert line.text.endswith("With ideal sensors: NO-GO.") and line.tone == "good"


def test_an_undetermined_line_gives_the_runs_that_would_decide_it():
    """The analysis's runs_to_decide, and its reason when no number of runs decides, are on the decision line."""
    results = results_of()
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    analysis["requirement_verdict"] = ("feature", np.array(["undetermined", "met"], dtype=object))
    analysis["runs_to_decide"] = ("feature", np.array([412.0, np.nan]))
    [line] = callouts(executive(results, analysis), "UNDETERMINED")
    assert "60 runs per sweep level cannot tell yet. About 412 ok runs per sweep data set (now 60) would decide it " \
           "if the estimate holds." in line.text
    analysis["runs_to_decide"] = ("feature", np.array([np.nan, np.nan]))
    analysis["runs_to_decide_reason"] = ("feature", np.array(["no number of runs decides it: a sweep level at the "
                                                             "requirement is needed", ""], dtype=object))
    [line] = callouts(executive(results, analysis), "UNDETERMINED")
    assert "No number of runs decides it: a sweep level at the requirement is needed." in line.text


def test_an_analysis_without_verdict_variables_gives_no_verdict():
    results = results_of()
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20).drop_vars("requirement_statement")
    page = executive(results, analysis)
    [note] = callouts(page, "Requirement verdict: not available")
    assert note.tone == "info" and [c for c in callouts(page) if c.link == "observability"] == [note]
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20).drop_vars("requirement_verdict")
    assert callouts(executive(results, analysis), "Requirement verdict: not available")


def test_the_question_states_the_requirement_the_analysis_states():
    results = results_of()
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    question = next(p.text for p in executive(results, analysis) if isinstance(p, Paragraph))
    assert question.startswith("What this campaign answers (verdict test): can the bench detect a backlash of 1 µm "
                               "(Table 9.3) with its sensors, when 2 of 2 sampled tolerances and conditions vary")
    analysis.attrs.update(requirement=2e-6, requirement_source="a tighter rig")
    question = next(p.text for p in executive(results, analysis) if isinstance(p, Paragraph))
    assert "detect a backlash of 2 µm (a tighter rig)" in question
    # an older analysis: the requirement stated on the minimum detectable backlash, else Table 9.3's
    del analysis.attrs["requirement"]
    analysis["minimum_detectable_backlash"].attrs.update(requirement=3e-6, requirement_source="the variable's own")
    question = next(p.text for p in executive(results, analysis) if isinstance(p, Paragraph))
    assert "detect a backlash of 3 µm (the variable's own)" in question
    older = analysis.drop_vars(["minimum_detectable_backlash"])
    question = next(p.text for p in executive(results, older) if isinstance(p, Paragraph))
    assert "detect a backlash of 1 µm (Table 9.3)" in question
    for unswept in (older.drop_dims("sweep_point"), older.isel(sweep_point=slice(0, 0))):  # no sweep, or an empty one
        question = next(p.text for p in executive(results, unswept) if isinstance(p, Paragraph))
        assert "the spec has no observability sweep, so no detection requirement is judged" in question


def test_page_one_names_no_raw_identifier():
    """Plain words on page 1: no true-signal suffix, no analysis attribute names, every term in the glossary."""
    results = results_of()
    page = executive(results)
    text = " ".join(getattr(block, "text", "") or getattr(block, "caption", "") for block in page)
    for raw in ("_true", "min_ok_runs", "first_order_index", "requirement_verdict", "data_sufficient"):
        assert raw not in text, raw
    [glossary] = [t for t in page if isinstance(t, Table) and t.caption == "Terms used on this page."]
    terms = " ".join(row[0] for row in glossary.rows)
    for term in ("GO / NO-GO / UNDETERMINED", "95 % bounds", "ideal sensors", "first-order index", "runs used"):
        assert term in terms


def test_the_data_set_table_gives_the_runs_used_and_mutes_the_short_ones():
    status = np.full((3, RUNS), "ok", dtype=object)
    status[1, 12:] = "error"  # b1: 12 ok runs, below MIN_OK_RUNS = 20
    status[2, :3] = "timeout"  # b2: 57 ok runs
    results = results_of(status=status)
    page = executive(results)
    [table] = [t for t in page if isinstance(t, Table) and t.caption.startswith("Data sets")]
    assert [row[2] for row in table.rows] == ["60 of 60", "12 of 60 (insufficient data: 12 ok run(s) < 20)", "57 of 60"]
    assert [row[4] for row in table.rows] == ["–", "–", "–"]  # no measured test given
    assert all(" (95 % interval " in row[3] and row[3].endswith(f"n = {n})") for row, n in zip(table.rows, (60, 12, 57),
                                                                                               strict=True))
    assert table.muted == (False, True, False)
    assert "at least 20 needed, the analysis's minimum" in table.caption
    assert "Measured test: none given" in table.caption
    # no condition shared by every data set: none stated as common; the conditions come from the spec's overrides
    assert "all share" not in table.caption and "read from the spec's overrides" in table.caption

    [failures] = callouts(page, "Failures:")
    assert failures.text == "Failures: 51 of 180 runs failed (left out of every statistic)." and failures.tone == "bad"
    assert failures.link == "failures"


def test_the_data_set_table_states_the_shared_conditions_and_their_source():
    results = results_of()
    spec = json.loads(results.attrs["spec_json"])
    for entry in spec["spec"]["datasets"]:
        entry["conditions"]["external_force"] = 0.0
    results.attrs["spec_json"] = json.dumps(spec)
    analysis = analysis_dataset(results, n_boot=20, sensitivity_boot=10)
    [table] = [t for t in executive(results, analysis) if isinstance(t, Table) and t.caption.startswith("Data sets")]
    assert "'nominal' (all share external force 0); read from the spec's overrides" in table.caption
    stored = {n: {"backlash": {"value": b, "unit": "m"}} for n, b in zip(NAMES, LEVELS, strict=True)}
    results.attrs["dataset_conditions"] = json.dumps(stored)
    [table] = [t for t in executive(results, analysis) if isinstance(t, Table) and t.caption.startswith("Data sets")]
    assert "read from the spec's overrides" not in table.caption and [r[1] for r in table.rows] == [
        "backlash 0 µm",
        "backlash 0.5 µm",
        "backlash 2 µm",
    ]


def test_an_older_analysis_is_judged_against_its_stated_or_the_default_minimum():
    """Without data_sufficient the report compares n_used with min_ok_runs, or with its own stated default (10)."""
    status = np.full((3, RUNS), "ok", dtype=object)
    status[1, 10:] = "error"  # b1: exactly 10 ok runs
    status[2, 9:] = "error"  # b2: 9
    results = results_of(status=status)
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20, min_ok_runs=3).drop_vars("data_sufficient")
    del analysis.attrs["min_ok_runs"]
    [table] = [t for t in executive(results, analysis) if isinstance(t, Table) and t.caption.startswith("Data sets")]
    assert table.muted == (False, False, True) and table.rows[2][2] == "9 of 60 (insufficient data: 9 ok run(s) < 10)"
    assert "at least 10 needed, the report's default; this analysis.nc states no minimum" in table.caption
    analysis.attrs["min_ok_runs"] = 11
    [table] = [t for t in executive(results, analysis) if isinstance(t, Table) and t.caption.startswith("Data sets")]
    assert table.muted == (False, True, True)


def test_every_run_ok_is_a_good_failures_callout_and_the_audit_sets_its_tone():
    results = results_of()
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    [failures] = callouts(executive(results, analysis), "Failures:")
    assert (failures.text, failures.tone) == ("Failures: 0 of 180 runs failed.", "good")
    for audit, tone in (
        ("met: auto is within the tolerance of full fidelity on every data set and feature", "good"),
        ("not met: auto differs from full fidelity (rule to fix): short/f", "bad"),
        ("undetermined: the audit's runs cannot resolve the tolerance: short/f", "info"),
        ("insufficient data: too few paired runs: short/f", "muted"),
        ("passed: mean shift 0.01 µm", "good"),  # results written before the three-way verdict
        ("FLAGGED (rule to fix): short/f", "bad"),
        ("not run (fidelity_audit.runs = 0)", "info"),
    ):
        results.attrs["fidelity_audit"] = audit
        [found] = callouts(executive(results, analysis), "Model check, fidelity audit")
        # a list of data-set/feature pairs is counted on page 1 (the Fidelity section lists them)
        shown = audit.replace(": short/f", ": 1 data-set/feature pair(s) in short (listed in the Fidelity section)")
        assert found.text.endswith(f": {shown}.") and found.tone == tone and found.link == "fidelity"
    del results.attrs["fidelity_audit"]
    [found] = callouts(executive(results, analysis), "Model check, fidelity audit")
    assert found.text.endswith("not recorded in results.nc.") and found.tone == "info"


def _influences(results, analysis) -> str:
    [text] = [c.text for c in callouts(executive(results, analysis)) if c.link == "correlations"]
    return text


def test_influences_rank_the_resolved_effect_sizes_with_their_data_set_and_n():
    results = results_of(gain_effect=0.5e-6)
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    analysis["first_order_index_flag"][:] = 0  # resolved indices first (60 runs are below the 200-run floor)
    cells = dict(feature="f", parameter="p.gain")
    analysis["effect_size"].loc[cells] = [1e-6, 3e-6, 2e-6]  # largest in b1
    analysis["effect_size"].loc[dict(feature="f", parameter="p.inert")] = [0.5e-6, 0.1e-6, 0.2e-6]
    analysis["first_order_index"].loc[cells] = [0.1, 0.634, 0.3]
    analysis["first_order_index_ci"].loc[cells] = [[0.05, 0.2], [0.412, 0.857], [0.1, 0.5]]
    analysis["first_order_index_ci"].loc[dict(feature="f", parameter="p.inert")] = [
        [0.01, 0.3],
        [-0.1, 0.2],
        [-0.1, 0.2],
    ]
    inert = float(analysis["first_order_index"].sel(dataset="b0", feature="f", parameter="p.inert"))
    assert _influences(results, analysis) == (
        "What moves f most: gain (p) moves it by 3 µm in b1 (explains 63 % of its variance, 95 % interval 41–86 %), "
        f"n = 60; inert (p) moves it by 500 nm in b0 (explains {inert * 100:.0f} % of its variance, 95 % interval "
        "1–30 %), n = 60."
    )
    # where the analysis withholds the index (first_order_index_flag), only the intervals are printed
    analysis["first_order_index_flag"].loc[dict(feature="f", parameter="p.gain", dataset="b1")] = 1
    analysis["effect_size_ci"].loc[dict(feature="f", parameter="p.gain", dataset="b1")] = [2.5e-6, 3.1e-6]
    text = _influences(results, analysis)
    assert ("gain (p) moves it by 2.5–3.1 µm in b1 (explains 41–86 % of its variance; interval only: the index itself "
            "is not resolved at this sample size)") in text
    assert "63 %" not in text  # the withheld index itself is not printed
    # ranked by what every row has, the lower bound of the effect size: a withheld 0–3.1 µm ranks below 2 µm
    analysis["effect_size_ci"].loc[dict(feature="f", parameter="p.gain", dataset="b1")] = [0.0, 3.1e-6]
    assert "gain (p) moves it by 2 µm in b2" in _influences(results, analysis)
    # an index whose interval reaches 0 is not an influence; none resolved: said so, nothing ranked
    analysis["first_order_index_ci"].loc[dict(feature="f", parameter="p.inert", dataset="b0", bound="lower")] = 0.0
    assert " inert (p) " not in _influences(results, analysis) + " "
    analysis["first_order_index_ci"].loc[dict(feature="f", bound="lower")] = -0.01
    assert _influences(results, analysis) == (
        "What moves f: no tolerance's first-order index is resolved above zero (95 % bootstrap interval) in any data "
        "set: the spread is not explained by a sampled tolerance at this sample size."
    )


def test_influences_fall_back_to_labelled_spearman_and_skip_short_data_sets():
    results = results_of(gain_effect=0.5e-6)
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    older = analysis.drop_vars(["effect_size", "effect_size_ci", "first_order_index", "first_order_index_ci"])
    older["spearman"].loc[dict(dataset="b1", feature="f", parameter="p.inert")] = np.nan  # no correlation there

    def expected(datasets):
        """Each parameter at its strongest data set (largest |rho|), ranked by that |rho|, written out."""
        items = []
        for parameter in ("p.gain", "p.inert"):
            rho = older["spearman"].sel(feature="f", parameter=parameter, dataset=datasets)
            dataset = str(rho["dataset"].values[int(np.nanargmax(np.abs(rho.values)))])
            lower, upper = older["spearman_ci"].sel(feature="f", parameter=parameter, dataset=dataset).values
            value = float(rho.sel(dataset=dataset))
            name = parameter.removeprefix("p.") + " (p)"
            items.append(
                (abs(value), f"{name} (ρ = {value:+.2f} [{lower:+.2f}, {upper:+.2f}] in {dataset}, n = 60)")
            )
        return (
            "What moves f, by the strongest |Spearman ρ| (a rank correlation, not an effect size: this analysis.nc "
            "has no effect_size): " + "; ".join(text for _, text in sorted(items, reverse=True)) + "."
        )

    older["spearman"].loc[dict(dataset="b2", feature="f", parameter="p.gain")] = 0.97  # the gain's strongest: b2
    assert _influences(results, older) == expected(["b0", "b1", "b2"]) and "in b2" in expected(["b0", "b1", "b2"])
    # a short data set is never chosen, even where its |rho| is the largest
    older["data_sufficient"].loc[dict(dataset="b2", feature="f")] = 0
    older["spearman"].loc[dict(dataset="b2", feature="f")] = [0.99, -0.99]
    assert _influences(results, older) == expected(["b0", "b1"])
    # every data set short: nothing is ranked
    short = analysis.copy()
    short["data_sufficient"] = xr.zeros_like(short["data_sufficient"])
    assert _influences(results, short) == (
        "What moves f: insufficient data in every data set (fewer than 20 ok runs); no influence is ranked."
    )


# --- reports.inputs ----------------------------------------------------------------------------------


def _write(results: xr.Dataset, folder, analysis: xr.Dataset | None = None):
    results.to_netcdf(folder / "results.nc", engine="netcdf4")
    if analysis is not None:
        analysis.to_netcdf(folder / "analysis.nc", engine="netcdf4")
    return folder / "results.nc"


def test_the_analysis_beside_the_results_is_used_and_checked(tmp_path):
    results = results_of()
    analysis = analysis_dataset(results, n_boot=20, sensitivity_boot=10)
    path = _write(results, tmp_path, analysis)
    inputs = load_inputs(path)
    assert not inputs.analysis_computed and [f.role for f in inputs.files] == ["results", "analysis"]
    assert [f.name for f in inputs.files] == ["results.nc", "analysis.nc"] and len(inputs.files[1].sha256) == 64
    assert inputs.spec["spec"]["name"] == "verdicts"
    # an analysis that states no source hash is accepted; one of another campaign is not
    analysis.attrs["source_spec_hash"] = ""
    analysis.to_netcdf(tmp_path / "unhashed.nc", engine="netcdf4")
    assert load_inputs(path, tmp_path / "unhashed.nc").files[1].name == "unhashed.nc"
    analysis.attrs["source_spec_hash"] = "cd" * 32
    analysis.to_netcdf(tmp_path / "other.nc", engine="netcdf4")
    with pytest.raises(
        ReportError, match=r"analysis of another campaign \(spec hash cdcdcdcdcdcdcdcd, results abababababababab\)"
    ):
        load_inputs(path, tmp_path / "other.nc")
    analysis.drop_vars(["overlap", "prcc"]).to_netcdf(tmp_path / "partial.nc", engine="netcdf4")
    with pytest.raises(ReportError, match="variable\\(s\\) prcc, overlap missing"):
        load_inputs(path, tmp_path / "partial.nc")
    with pytest.raises(ReportError, match="is not a file"):
        load_inputs(tmp_path)
    with pytest.raises(ReportError, match="campaign results file not found"):
        load_inputs(tmp_path / "missing.nc")
    (tmp_path / "garbage.nc").write_bytes(b"not netCDF" * 10)
    with pytest.raises(ReportError, match="cannot be read as a netCDF campaign analysis file"):
        load_inputs(path, tmp_path / "garbage.nc")


def test_results_checks_name_each_problem(tmp_path):
    results = results_of()
    broken = results.drop_vars(["wall_time"])
    broken.attrs["spec_json"] = "{not json"
    with pytest.raises(ReportError, match="variable 'wall_time' missing; spec_json attribute is not valid JSON"):
        load_inputs(_write(broken, tmp_path))
    broken = results.copy()
    broken.attrs["spec_json"] = json.dumps({"spec": {}})
    with pytest.raises(ReportError, match="spec_json attribute missing or incomplete \\(no 'datasets'\\)"):
        load_inputs(_write(broken, tmp_path))
    broken = results.copy()
    for name in ("f", "f_true"):
        broken[name].attrs["role"] = "sampled"
    with pytest.raises(ReportError, match="no feature variable"):
        load_inputs(_write(broken, tmp_path))


def test_an_accuracy_study_along_another_dimension_is_refused(tmp_path):
    path = _write(results_of(), tmp_path, analysis_dataset(results_of(), n_boot=20, sensitivity_boot=10))
    accuracy = xr.Dataset(
        {name: (("run",), np.zeros(2)) for name in ("wall_time", "feature_error", "status", "method")}
    )
    accuracy.to_netcdf(tmp_path / "good.nc")
    assert [f.role for f in load_inputs(path, accuracy_path=tmp_path / "good.nc").files] == [
        "results",
        "analysis",
        "accuracy",
    ]
    accuracy["feature_error"] = (("run", "feature"), np.zeros((2, 1)))
    accuracy.to_netcdf(tmp_path / "bad.nc")
    with pytest.raises(ReportError, match="must all lie along the dimension 'run'"):
        load_inputs(path, accuracy_path=tmp_path / "bad.nc")


# --- the observability section and the first-order table: brackets and withheld indices ---------------------------


def _section_blocks(module, results: xr.Dataset, analysis: xr.Dataset) -> list:
    inputs = Inputs(results, analysis, None, json.loads(results.attrs["spec_json"]), (), False)
    return list(module.build(Builder(inputs)))


def test_the_observability_section_gives_the_bracket_never_an_interpolated_value():
    """Noise 0.1 µm on levels 0, 0.5 and 2 µm: 0.5 µm is detected, 0 is not; the minimum lies between those two
    adjacent levels. The section quotes the statement, names the bracket in the figure caption and prints no value
    between the levels (the analysis holds none)."""
    from reports.sections import observability

    results = results_of()
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    assert np.isnan(analysis["minimum_detectable_backlash"]).all()
    blocks = _section_blocks(observability, results, analysis)
    texts = [getattr(b, "text", "") or getattr(b, "caption", "") for b in blocks]
    page_one = executive(results, analysis)  # the detection figure is page 1's
    for feature in ("f", "f_true"):
        statement = str(analysis["requirement_statement"].sel(feature=feature).item())
        assert statement.startswith("met: minimum detectable backlash between the adjacent sweep levels 0 µm (b0) and "
                                    "0.5 µm (b1) (")
        assert f"{feature}: {statement}" in texts
    [caption] = [b.caption for b in page_one if isinstance(b, Figure) and b.key == "detection-sweep"]
    assert "nothing is drawn between them, where no run was made" in caption and "bound" in caption
    assert not any("interpolated linearly" in t for t in texts)
    assert any("lies between 0 and that level, and no value inside is resolved" in t for t in texts)
    assert not any("never reaches" in t for t in texts)
    assert not [b for b in blocks if isinstance(b, Figure) and b.key == "detection-sweep"]  # drawn once, on page 1


def test_the_separation_map_says_why_a_column_is_blank():
    """A reference data set below the detection floor (58 < 59 ok runs) sets no threshold: its column is blank and the
    caption gives the floor and the analysis's reason."""
    from reports.sections import observability

    status = np.full((3, RUNS), "ok", dtype=object)
    status[1, 58:] = "error"
    results = results_of(status=status)
    analysis = analysis_dataset(results, n_boot=20, sensitivity_boot=10)
    [caption] = [b.caption for b in _section_blocks(observability, results, analysis)
                 if isinstance(b, Figure) and b.key == "separation-f"]
    assert ("Blank columns (b1): insufficient data for a threshold, fewer than 59 ok runs: with fewer, not even the "
            "largest run bounds the 95 % quantile that sets the detection threshold from above with 95 % confidence."
            in caption)


def _first_order_table(results, analysis) -> Table:
    from reports.sections import correlations

    [table] = [t for t in _section_blocks(correlations, results, analysis)
               if isinstance(t, Table) and "first-order index" in t.caption]
    return table


def test_the_first_order_table_gives_the_interval_only_where_the_index_is_withheld():
    """60 runs, below the first-order floor (200): every row shows its interval only, greyed, with the reason; an
    index given by the analysis is shown with its interval; one outside its interval says so. Rows are ranked by the
    lower bound of the interval."""
    results = results_of(gain_effect=0.5e-6)
    analysis = analysis_dataset(results, n_boot=20, sensitivity_boot=50)
    table = _first_order_table(results, analysis)
    rows = [r for r in table.rows if r[0] == "f"]
    assert all(r[3].startswith("interval only: [") and "index withheld: 60 ok runs < 200" in r[7] for r in rows)
    assert all(table.muted) and all(r[4].startswith("[") for r in rows)  # the effect size as its interval too
    for name in NAMES:  # the gain (a 0.5 µm effect against 0.1 µm noise) ranks first in every data set
        assert [r[2] for r in rows if r[1] == name][0] == "p.gain"
    cell = dict(dataset="b1", feature="f", parameter="p.gain")
    analysis["first_order_index_flag"].loc[cell] = 0
    analysis["first_order_index"].loc[cell] = 0.634
    analysis["first_order_index_ci"].loc[cell] = [0.412, 0.857]
    analysis["effect_size"].loc[cell] = 3e-6
    row = next(r for r in _first_order_table(results, analysis).rows if r[:3] == ("f", "b1", "p.gain"))
    assert row[3:5] == ("0.63 [0.41, 0.86]", "3 µm") and row[6:] == ("yes", "–")
    analysis["first_order_index_flag"].loc[cell] = 2
    row = next(r for r in _first_order_table(results, analysis).rows if r[:3] == ("f", "b1", "p.gain"))
    assert row[3] == "interval only: [0.41, 0.86]"
    assert row[7] == "index withheld: the estimate fell outside its own bootstrap interval"


def test_an_interval_reads_in_the_unit_that_shows_it():
    """Effect sizes and their intervals: one prefix for both bounds, chosen by the larger (never "0 m")."""
    from reports.units import quantity_range

    assert quantity_range(0.0, 3.1e-6, "m") == "0–3.1 µm"
    assert quantity_range(1.04e-7, 4.44e-7, "m") == "100–440 nm"
    assert quantity_range(0.0, 0.0, "m") == "0–0 m"
    assert quantity_range(0.2, 0.5, "1") == "0.2–0.5"


@pytest.mark.parametrize("verdict", ["met", "not met", "undetermined", "insufficient data"])
def test_each_decision_line_of_page_one_gives_its_n(verdict):
    """Issue 42: page 1 has one line per requirement, each with the runs it rests on (60 ok runs per sweep level here),
    and the answer in a picture right below the detection decisions."""
    results = results_of()
    analysis = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    analysis["requirement_verdict"] = ("feature", np.array([verdict, "met"], dtype=object))
    page = executive(results, analysis)
    lines = [c for c in page if isinstance(c, Callout) and " — " in c.text
             and c.text.split(" — ", 1)[0] in ("GO", "NO-GO", "UNDETERMINED", "NO DATA")]
    detection = [c for c in lines if " — Detect a " in c.text]
    assert len(detection) == 1  # f; its ideal-sensor reading f_true on the same line
    assert all(re.search(r"\b60 (ok )?runs per sweep level\b", c.text) for c in detection), detection
    figure = next(k for k, block in enumerate(page) if isinstance(block, Figure))
    assert page[figure].key == "detection-sweep" and page.index(detection[0]) == figure - 1


def test_a_separation_matrix_that_reads_one_number_is_a_sentence():
    """Issue 42: 7 × 7 cells of 1.00 say nothing a sentence does not; a matrix with any other cell is drawn."""
    from reports.sections import observability

    results = results_of()
    analysis = analysis_dataset(results, n_boot=20, sensitivity_boot=10)
    pairs = len(NAMES) * (len(NAMES) - 1)
    analysis["detection_probability"] = xr.ones_like(analysis["detection_probability"])
    analysis["overlap"] = xr.zeros_like(analysis["overlap"]).where(
        analysis["dataset"] != analysis["reference"], 1.0)  # 1 on the diagonal, by definition
    blocks = _section_blocks(observability, results, analysis)
    texts = [b.text for b in blocks if isinstance(b, Paragraph)]
    assert any(f"every one of the {pairs} pairs of distinct data sets reads 1.00" in t for t in texts)
    assert any(f"every one of the {pairs} pairs of distinct data sets reads 0.00" in t for t in texts)
    assert not [b for b in blocks if isinstance(b, Figure) and b.key.startswith(("separation-", "overlap-"))]
    analysis["detection_probability"] = analysis["detection_probability"].where(
        (analysis["dataset"] != "b0") | (analysis["reference"] != "b2"), 0.99)
    keys = [b.key for b in _section_blocks(observability, results, analysis) if isinstance(b, Figure)]
    assert "separation-f" in keys and "overlap-f" not in keys
