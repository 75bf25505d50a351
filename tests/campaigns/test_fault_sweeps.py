"""Several fault sweeps in one spec (issue 42, item 1) and one fidelity along each sweep (item 3).

A spec's ``[[observability]]`` tables each get their own verdict variables; the first keeps the names of a spec with
one sweep, so a single ``[observability]`` table is the same spec (same hash) and the same analysis as before. The
bench campaign runs every member of a sweep at one set of fidelity levels (:func:`sweep_fidelity`), and leaves a
spec whose sweeps already agree unchanged.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from campaign_helpers import SYNTHETIC_SPEC, load, write_spec

from campaigns.analysis.observability import observability_analysis
from campaigns.analysis.settings import AnalysisSettings
from campaigns.bench.campaign import load_spec as load_bench_spec
from campaigns.bench.campaign import sweep_fidelity
from campaigns.runner.execution import build_request
from campaigns.runner.sampling import sample
from campaigns.runner.spec import SpecError
from reports.detection import sweep_views
from twin.levels import SUBSYSTEMS

SPECS = Path(__file__).parents[2] / "campaigns" / "specs"
GOLDEN = Path(__file__).parent / "data" / "golden_thesis_small.toml"
PRELOAD_SWEEP = """
[[observability]]
sweep = ["ds4", "ds6", "ds2"]

[[observability]]
condition = "preload"
reference = "ds4"
sweep = ["ds4", "p800"]
requirement = 200.0
requirement_source = "test"

[[datasets]]
name = "p800"
scene = "ds4"
conditions = { backlash = 0.0, preload = 800.0, external_force = 0.0 }
"""


def test_one_table_in_an_array_is_the_single_table_spec(tmp_path):
    single = load(write_spec(tmp_path, ""))
    array = load(write_spec(tmp_path, '[[observability]]\nsweep = ["ds4", "ds6", "ds2"]\n'))
    assert array.spec_hash() == single.spec_hash()
    assert [s.sweep for s in array.sweeps] == [["ds4", "ds6", "ds2"]] and array.further_sweeps == []


def test_two_sweeps_validate_and_keep_their_order(tmp_path):
    path = tmp_path / "two.toml"  # the data sets added to the synthetic spec's (a list in an override replaces them)
    path.write_text(SYNTHETIC_SPEC.read_text().replace('[observability]\nsweep = ["ds4", "ds6", "ds2"]\n', "")
                    + PRELOAD_SWEEP)
    spec = load(path)
    assert [(s.condition, s.sweep) for s in spec.sweeps] == [("backlash", ["ds4", "ds6", "ds2"]),
                                                              ("preload", ["ds4", "p800"])]
    assert json.loads(spec.to_json())["spec"]["further_sweeps"][0]["requirement"] == 200.0


@pytest.mark.parametrize(("table", "problem"), [
    ('[[observability]]\nsweep = ["ds4", "ds6"]\n[[observability]]\nsweep = ["ds4", "ds2"]\n',
     "observability: backlash swept by more than one table"),
    ('[[observability]]\nsweep = ["ds4", "ds6"]\n[[observability]]\ncondition = "preload"\nreference = "ds4"\n'
     'requirement = 200.0\nsweep = ["ds4", "nope"]\n', "observability[1].sweep: unknown data set(s) nope"),
    ('[[observability]]\nsweep = ["ds4", "ds6"]\n[[observability]]\ncondition = "preload"\nsweep = ["ds4", "ds5"]\n',
     "observability[1].reference: required for a preload sweep"),
    ('[[observability]]\nsweep = ["ds4", "ds6"]\n[[observability]]\ncondition = "preload"\nreference = "ds4"\n'
     'requirement = -1.0\nsweep = ["ds4", "ds5"]\n', "observability[1].requirement"),
    ('[[observability]]\nsweep = ["ds4", "ds6"]\n[[observability]]\n', "observability[1].sweep: empty"),
    ("observability = []\n", "observability: give one [observability] table"),
])
def test_bad_sweep_tables_are_named_by_their_place(tmp_path, table, problem):
    with pytest.raises(SpecError) as error:
        load(write_spec(tmp_path, table))
    assert any(p.startswith(problem) for p in error.value.problems), error.value.problems


def test_a_preload_sweep_runs_at_one_fidelity():
    """The automatic choice takes the quasi-static screw axial at 1000 N only (``min_preload``), so the members'
    choices differ: the whole sweep then runs the full model (a mixture of their levels is a model no speed
    measurement covers), the 1000 N reference with the dynamic shaft like the lower preloads."""
    spec = load_bench_spec(SPECS / "preload_loss.toml")
    swept = sweep_fidelity(spec)
    changed = {d.name: d.fidelity for d in swept.datasets if d.fidelity is not None}
    assert "p1000" in changed and changed["p1000"]["screw_axial"] == "dynamic"
    sweep = {d.name for d in swept.datasets if d.name.startswith("p")}
    assert set(changed) == sweep
    assert all(levels == {name: SUBSYSTEMS[name].full for name in SUBSYSTEMS} for levels in changed.values())
    assert swept.spec_hash() != spec.spec_hash()  # the levels are part of the spec, recorded in results.nc
    # and the runs take them: every member's request carries its sweep's levels
    samples = sample(swept)
    names = [d.name for d in swept.datasets]
    assert build_request(swept, samples, names.index("p1000"), 0).solver["fidelity"] == changed["p1000"]
    assert build_request(swept, samples, names.index("p800"), 0).solver["fidelity"] == changed["p800"]


@pytest.mark.parametrize("path", [GOLDEN, SPECS / "thesis_backlash.toml", SPECS / "observability.toml"])
def test_a_spec_whose_sweep_agrees_is_unchanged(path):
    """The golden campaign's sweep (ds4, ds2) and the thesis's already share their levels: the same spec, the same
    hash, so the golden results stand."""
    spec = load_bench_spec(path)
    assert sweep_fidelity(spec) is spec


def _results(spec_data: dict, runs: int = 80, seed: int = 3) -> xr.Dataset:
    """Synthetic results: feature = backlash + preload loss x 1e-9 m/N + noise (0.1 um), every run ok."""
    names = ["b0", "b1", "b5", "p800", "p600"]
    backlash = np.array([0.0, 1e-6, 5e-6, 0.0, 0.0])
    preload = np.array([1000.0, 1000.0, 1000.0, 800.0, 600.0])
    rng = np.random.default_rng(seed)
    values = (backlash + (1000.0 - preload) * 1e-9)[:, None] + 0.1e-6 * rng.standard_normal((len(names), runs))
    return xr.Dataset(
        {"f": (("dataset", "run"), values, {"role": "feature", "units": "m"}),
         "status": (("dataset", "run"), np.full(values.shape, "ok", dtype=object)),
         "condition_backlash": ("dataset", backlash), "condition_preload": ("dataset", preload)},
        coords={"dataset": names}, attrs={"spec_json": json.dumps({"spec": spec_data})})


BACKLASH = {"sweep": ["b0", "b1", "b5"], "condition": "backlash", "reference": None, "requirement": None,
            "requirement_source": ""}
PRELOAD = {"sweep": ["b0", "p800", "p600"], "condition": "preload", "reference": "b0", "requirement": 200.0,
           "requirement_source": "test"}


def test_each_sweep_has_its_own_verdict_and_the_first_keeps_its_names():
    settings = AnalysisSettings(n_boot=200)
    one = observability_analysis(_results({"observability": BACKLASH}), settings)
    two = observability_analysis(_results({"observability": BACKLASH, "further_sweeps": [PRELOAD]}), settings)
    alone = observability_analysis(_results({"observability": PRELOAD}), settings)
    xr.testing.assert_identical(two[list(one.data_vars)], one)  # the first sweep: bit for bit as alone
    assert list(two["sweep_point_preload"].values) == ["b0", "p800", "p600"]
    # 200 N moves the feature 2 sigma: the verdict and the detection probabilities are those of the sweep alone
    # (the bootstrap streams differ, the point estimates do not)
    assert two["requirement_verdict_preload"].values.tolist() == alone["requirement_verdict"].values.tolist()
    np.testing.assert_array_equal(two["sweep_detection_probability_preload"].values,
                                  alone["sweep_detection_probability"].values)
    assert two["requirement_verdict_preload"].attrs["requirement"] == 200.0
    (_, first), (key, view) = sweep_views(two)
    assert first is two and key == "_preload"
    assert view.attrs["observability_condition"] == "preload" and view.attrs["requirement"] == 200.0
    assert list(view["sweep_point"].values) == ["b0", "p800", "p600"]
    xr.testing.assert_equal(view["sweep_preload_loss"], two["sweep_preload_loss_preload"].rename(
        sweep_point_preload="sweep_point"))
    assert "sweep_backlash" not in view and view["requirement_verdict"].values.tolist() == \
        two["requirement_verdict_preload"].values.tolist()


def test_the_printed_summary_gives_each_sweeps_verdict():
    """What `twin campaign run --analyze` prints: the first sweep's statement per feature, then each further sweep's,
    labelled by its condition."""
    from campaigns.analysis.campaign_analysis import summary

    two = observability_analysis(_results({"observability": BACKLASH, "further_sweeps": [PRELOAD]}),
                                 AnalysisSettings(n_boot=200))
    features = [str(f) for f in two["feature"].values]
    shown = two.assign(n_used=xr.DataArray(np.full((len(features), 1), 100), dims=("feature", "dataset"),
                                           coords={"feature": features, "dataset": ["b0"]}))
    shown.attrs["min_ok_runs"] = 20
    statements, _ = summary(shown)
    for feature in features:
        assert f"{feature}: {two['requirement_statement'].sel(feature=feature).item()}" in statements
        assert (f"{feature} (preload sweep): {two['requirement_statement_preload'].sel(feature=feature).item()}"
                in statements)


# --- each sweep's features (the features its verdicts are about) ---

def test_a_sweep_names_its_features_and_leaving_them_out_keeps_the_hash(tmp_path):
    """Absent or empty, a sweep's ``features`` is every feature: the spec, and its hash, as before sweeps named
    theirs (the thesis and golden specs keep their results directories); named, it is part of the spec."""
    plain = load(write_spec(tmp_path, '[[observability]]\nsweep = ["ds4", "ds6", "ds2"]\n'))
    empty = load(write_spec(tmp_path, '[[observability]]\nsweep = ["ds4", "ds6", "ds2"]\nfeatures = []\n'))
    named = load(write_spec(tmp_path, '[[observability]]\nsweep = ["ds4", "ds6", "ds2"]\n'
                                      'features = ["backlash_feature"]\n'))
    assert empty.spec_hash() == plain.spec_hash() != named.spec_hash()
    assert "features" not in json.loads(plain.to_json())["spec"]["observability"]
    assert named.observability.features == ["backlash_feature"]


@pytest.mark.parametrize(("table", "path"), [
    ('[observability]\nsweep = ["ds4", "ds6", "ds2"]\nfeatures = ["backlash_featur"]\n', "observability.features"),
    ('[[observability]]\nsweep = ["ds4", "ds6"]\n[[observability]]\ncondition = "preload"\nreference = "ds4"\n'
     'requirement = 200.0\nsweep = ["ds4", "ds5"]\nfeatures = ["drag_torque_feature"]\n', "observability[1].features"),
])
def test_a_feature_the_campaign_does_not_measure_is_one_problem_naming_the_allowed(tmp_path, table, path):
    with pytest.raises(SpecError) as error:
        load(write_spec(tmp_path, table))
    named = [p for p in error.value.problems if p.startswith(f"{path}: ")]
    assert len(named) == 1, error.value.problems
    assert "allowed: backlash_feature, backlash_feature_true" in named[0]


def test_a_feature_named_twice_is_refused(tmp_path):
    with pytest.raises(SpecError) as error:
        load(write_spec(tmp_path, '[observability]\nsweep = ["ds4", "ds6", "ds2"]\n'
                                  'features = ["backlash_feature", "backlash_feature"]\n'))
    assert "observability.features: backlash_feature listed twice" in error.value.problems


def _two_feature_results(spec_data: dict, runs: int = 60) -> xr.Dataset:
    """:func:`_results` with a second feature ``g`` = preload loss x 1e-8 m/N + noise (0.1 µm), blind to the
    backlash, and ``f`` blind to the preload loss: each sweep's verdict is about one of them."""
    results = _results(spec_data, runs=runs)
    backlash, preload = results["condition_backlash"].values, results["condition_preload"].values
    rng = np.random.default_rng(11)
    shape = results["f"].shape
    f = backlash[:, None] + 0.1e-6 * rng.standard_normal(shape)
    g = ((1000.0 - preload) * 1e-8)[:, None] + 0.1e-6 * rng.standard_normal(shape)
    return results.assign(
        f=(("dataset", "run"), f, {"role": "feature", "units": "m"}),
        g=(("dataset", "run"), g, {"role": "feature", "units": "m"}),
        **{"p.gain": (("dataset", "run"), rng.uniform(-1, 1, shape), {"role": "sampled", "units": "1"}),
           "failure_reason": (("dataset", "run"), np.full(shape, "", dtype=object)),
           "wall_time": (("dataset", "run"), np.ones(shape))},
    ).assign_coords(run=np.arange(runs)).assign_attrs(spec_hash="ab" * 32)


TWO_SWEEPS = {"name": "two", "description": "", "base": {"scene": "nominal"},
              "datasets": [{"name": n} for n in ["b0", "b1", "b5", "p800", "p600"]],
              "observability": {**BACKLASH, "features": ["f"]}, "further_sweeps": [{**PRELOAD, "features": ["g"]}]}


@pytest.fixture(scope="module")
def two_sweeps():
    from campaigns.analysis.campaign_analysis import analysis_dataset

    results = _two_feature_results(TWO_SWEEPS)
    return results, analysis_dataset(results, n_boot=50, sensitivity_boot=10)


def test_the_analysis_marks_each_sweeps_features(two_sweeps):
    """Every feature gets each sweep's verdict (the analysis's shape does not depend on the list); the mark says which
    the sweep is about, and without a list every feature is marked."""
    _, analysis = two_sweeps
    assert analysis["sweep_feature"].values.tolist() == [1, 0]  # features f, g
    assert analysis["sweep_feature_preload"].values.tolist() == [0, 1]
    assert analysis["requirement_verdict"].sel(feature="f").item() == "met"  # 1 µm moves f 10 sigma
    assert analysis["requirement_verdict_preload"].sel(feature="g").item() == "met"  # 200 N moves g 20 sigma
    unnamed = observability_analysis(_two_feature_results({"observability": BACKLASH, "further_sweeps": [PRELOAD]}),
                                     AnalysisSettings(n_boot=50))
    assert unnamed["sweep_feature"].values.tolist() == unnamed["sweep_feature_preload"].values.tolist() == [1, 1]


def test_the_printed_summary_gives_each_sweep_its_own_features(two_sweeps):
    from campaigns.analysis.campaign_analysis import summary

    _, analysis = two_sweeps
    statements, _ = summary(analysis)
    assert [s.split(": ", 1)[0] for s in statements] == ["f", "g (preload sweep)"]


def test_page_one_gives_each_sweep_its_own_features_in_words_and_pictures(two_sweeps, monkeypatch):
    """Page 1: the backlash requirement's decision with f alone, the preload loss's with g alone, and each sweep's
    figure with that feature's points and verdict alone."""
    import reports.detection
    from reports.builder import Builder
    from reports.inputs import Inputs
    from reports.model import Callout
    from reports.sections import executive

    drawn = []
    draw = reports.detection.detection
    monkeypatch.setattr(reports.detection, "detection", lambda series, **kw: drawn.append(
        ([s.label for s in series], [b[0] for b in kw["bounds"]])) or draw(series, **kw))
    results, analysis = two_sweeps
    inputs = Inputs(results, analysis, None, json.loads(results.attrs["spec_json"]), (), False)
    page = executive.build(Builder(inputs))
    decisions = [c.text for c in page if isinstance(c, Callout) and " — Detect a " in c.text]
    assert [d.split(":", 1)[0] for d in decisions] == ["GO — Detect a 1 µm backlash (Table 9.3) with f",
                                                       "GO — Detect a 200 N preload loss (test) with g"]
    assert [(labels, [b.split(":")[0] for b in bounds]) for labels, bounds in drawn] == [(["f"], ["f"]),
                                                                                        (["g"], ["g"])]
