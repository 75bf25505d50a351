"""Known answers of the level search (campaigns.workflows.level_search, issue 42 item 2) on the synthetic model.

The spec: the synthetic model's reference (no backlash) and one level at 5 µm, the offset sampled from a Gaussian
of standard deviation ``sigma``. Every run's feature is then ``backlash + N(0, s)`` with ``s^2 = NOISE_SIGMA^2 +
sigma^2``, the detection threshold the reference's ``1 - FALSE_ALARM_RATE`` quantile, so the true minimum detectable
backlash has the closed form ``(z(1 - FALSE_ALARM_RATE) + z(POWER)) s`` (a shift of the normal by the two quantiles):
0.82, 1.05 and 1.33 µm for sigma = 0.15, 0.25, 0.35 µm, below, at and above the 1 µm requirement.

Rates over seeds: each test runs a few dozen searches with fixed seeds and allows the count of misses that a true
miss rate of 5 % exceeds with less than 1 % probability (binomial), so it fails when the rate is worse than stated,
not on an unlucky seed. The runs of a search are few (59-320 per level) and the bootstrap small (200 replicates),
so the module stays fast enough for CI (its cost: docs/level_search.md).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from campaigns.runner.execution import build_request
from campaigns.runner.runs import execute
from campaigns.runner.sampling import sample
from campaigns.runner.spec import load_spec
from campaigns.runner.synthetic import NOISE_SIGMA, SYNTHETIC_CATALOG, synthetic_run
from campaigns.statistics.defaults import FALSE_ALARM_RATE, POWER
from campaigns.workflows.level_search import (
    LOG_NAME,
    LevelSearchError,
    Settings,
    look_confidence,
    probit_fit,
    probit_level,
    search,
    statement,
    store,
)

FEATURE = "backlash_feature"
REQUIREMENT = 1e-6
SEEDS = 30
#: Misses allowed among SEEDS searches: a true rate of 5 % exceeds it with probability below 1 %.
ALLOWED = int(stats.binom.ppf(0.99, SEEDS, 1.0 - 0.95))


def write_spec(directory: Path, sigma_um: float, seed: int, runs: int = 59, extra: str = "") -> Path:
    path = directory / f"spec_{sigma_um}_{seed}.toml"
    path.write_text(f"""name = "bracket"
root_seed = {seed}
runs_per_dataset = {runs}
features = ["{FEATURE}"]

[base]
scene = "ds2"
parameters = "synthetic"

[execution]
isolation = "none"

[traces]
runs_per_dataset = 0

[observability]
sweep = ["b0", "b5"]

[[datasets]]
name = "b0"
conditions = {{ backlash = 0.0 }}

[[datasets]]
name = "b5"
conditions = {{ backlash = 5e-6 }}
{extra}
[[uncertainties]]
target = "synthetic.offset"
distribution = "gaussian"
sigma = {sigma_um}
unit = "um"
""")
    return path


def true_minimum(sigma_um: float) -> float:
    """The closed form of the module docstring [m]."""
    spread = math.hypot(NOISE_SIGMA, sigma_um * 1e-6)
    return float((stats.norm.ppf(1.0 - FALSE_ALARM_RATE) + stats.norm.ppf(POWER)) * spread)


def run_search(path: Path, **settings):
    return search(path, Settings(feature=FEATURE, n_boot=200, **settings), run_function=synthetic_run,
                  catalog=SYNTHETIC_CATALOG)


def right(verdict: str, truth: float) -> bool | None:
    """Whether a decided verdict is right (None: undetermined, neither right nor wrong)."""
    if verdict == "undetermined":
        return None
    return (verdict == "met") == (truth <= REQUIREMENT)


@pytest.mark.parametrize("sigma_um", [0.15, 0.25, 0.35])
def test_over_many_seeds_the_bounds_hold_the_true_minimum_and_the_verdict_is_right(tmp_path, sigma_um):
    """Levels to 0.5 µm from a 0-5 µm sweep: the bounds contain the closed-form minimum and no decided verdict is
    wrong, each at least at 95 % over 30 seeds; every level's runs are counted in the runs reported."""
    truth = true_minimum(sigma_um)
    missed, wrong, decided = 0, 0, 0
    for seed in range(SEEDS):
        result = run_search(write_spec(tmp_path, sigma_um, seed), resolution=0.5e-6)
        low, high = result.last.bounds
        missed += not low <= truth <= high
        verdict = right(result.last.verdict, truth)
        decided += verdict is not None
        wrong += verdict is False
        assert REQUIREMENT in result.last.levels.values()  # the requirement is always tried
        assert result.runs_used == 59 * len(result.last.levels)
        assert f"{result.runs_used} runs in all" in statement(result)
        assert result.resolved or result.stop_reason.startswith("level budget")
    assert missed <= ALLOWED and wrong <= ALLOWED
    if abs(truth - REQUIREMENT) > 0.2e-6:  # far from the requirement, 59 runs per level decide most seeds
        assert decided >= SEEDS // 2


@pytest.mark.parametrize("sigma_um", [0.15, 0.25, 0.35])
def test_runs_grow_in_stages_until_the_verdict_is_decided_at_its_confidence_over_the_looks(tmp_path, sigma_um):
    """Three looks at 80, 160, 320 runs per level (Bonferroni: each at 98.3 %, so the first look needs 80 runs), only
    the requirement level added: the verdicts are right at least at 95 % over 30 seeds, and a search stops at the
    first look that decides it."""
    truth = true_minimum(sigma_um)
    wrong, decided = 0, 0
    for seed in range(SEEDS):
        result = run_search(write_spec(tmp_path, sigma_um, seed), stages=[80, 160, 320])
        verdict = right(result.last.verdict, truth)
        decided += verdict is not None
        wrong += verdict is False
        looks = [s.look for s in result.steps]
        assert all(s.verdict == "undetermined" for s in result.steps[:-1] if s.look < looks[-1])
        assert result.runs_used == result.last.runs_per_level * 3  # b0, b5 and the requirement, grown alike
        assert result.last.confidence == pytest.approx(look_confidence(0.95, 3))
    assert wrong <= ALLOWED
    if abs(truth - REQUIREMENT) > 0.2e-6:
        assert decided >= SEEDS * 0.8


def test_a_level_has_the_same_numbers_whatever_the_order_it_was_added_in(tmp_path):
    """Bisection and the monotone fit add levels in different orders; a level both add has the same runs, bit for
    bit, and so has that level written by hand into a spec at another position (the reference's data set with the
    backlash changed and the reference's seeds): the numbers of a level depend on the spec and its size only."""
    path = write_spec(tmp_path, 0.25, 7)
    a, b = run_search(path, resolution=0.25e-6), run_search(path, resolution=0.25e-6, method="monotone_fit")
    common = sorted(set(a.added) & set(b.added))
    assert a.added != b.added and len(common) >= 2  # different orders, shared levels
    for name in common:
        for i in range(59):
            assert a.records[name, i]["features"] == b.records[name, i]["features"]
    name = common[-1]
    size = a.last.levels[name]
    by_hand = write_spec(tmp_path, 0.25, 7, extra=f"""
[[datasets]]
name = "{name}"
seeds_from = "b0"
conditions = {{ backlash = {size!r} }}
""")
    spec = load_spec(by_hand, catalog=SYNTHETIC_CATALOG)
    d = [x.name for x in spec.datasets].index(name)
    samples = sample(spec)
    for i in range(59):
        assert execute(synthetic_run, build_request(spec, samples, d, i))["features"] == a.records[name, i]["features"]


def test_the_final_campaign_is_stored_and_analysed_like_fixed_levels(tmp_path):
    """results.nc holds every level (the added ones after the spec's, the sweep by size) with the search's numbers,
    re-running a run of it gives them again, and the analysis reads its verdict from them as from any campaign."""
    result = run_search(write_spec(tmp_path, 0.15, 3), resolution=0.5e-6)
    path = store(result, tmp_path / "out", run_function=synthetic_run)
    with xr.open_dataset(path) as results:
        names = [str(n) for n in results["dataset"].values]
        assert names[:2] == ["b0", "b5"] and set(names[2:]) == set(result.added)
        for name in result.added:
            stored = results[FEATURE].sel(dataset=name).values
            assert np.array_equal(stored, [result.records[name, i]["features"][FEATURE] for i in range(59)])
        spec = json.loads(results.attrs["spec_json"])["spec"]
        sweep = spec["observability"]["sweep"]
        assert [result.last.levels[n] for n in sweep] == sorted(result.last.levels.values())
    final = result.spec
    samples = sample(final)
    d = len(final.datasets) - 1
    record = execute(synthetic_run, build_request(final, samples, d, 58))
    assert record["features"] == result.records[final.datasets[d].name, 58]["features"]
    with xr.open_dataset(path.with_name("analysis.nc")) as analysis:
        assert str(analysis["requirement_verdict"].sel(feature=FEATURE).item()) in ("met", "undetermined")
    log = json.loads(path.with_name(LOG_NAME).read_text())
    assert log["steps"][-1]["runs_used"] == result.runs_used and log["statement"] == statement(result)


def _never(request):
    raise AssertionError("a run started although the plan is invalid")


@pytest.mark.parametrize(("settings", "runs", "words"), [
    ({"resolution": 0.01e-6, "max_levels": 4}, 59,
     "resolution: 0.01 µm is finer than the sweep can resolve with max_levels = 4: its widest gap, 4 µm, needs 9 "
     "bisections besides the requirement level; allowed: at least 0.5 µm"),
    ({"resolution": 0.5e-6, "runs": 150}, 59, "runs: a budget of 150 runs is below the floor of 177"),
    ({"resolution": 0.5e-6}, 40, "runs_per_dataset: 40 runs per level at the first look is below the floor of 59"),
    ({"stages": [70, 140]}, 59, "stages: 70 runs per level at the first look is below the floor of 72"),
])
def test_bad_plans_get_one_clear_error_before_any_run(tmp_path, settings, runs, words):
    with pytest.raises(LevelSearchError) as error:
        search(write_spec(tmp_path, 0.25, 0, runs=runs), Settings(feature=FEATURE, **settings), run_function=_never,
               catalog=SYNTHETIC_CATALOG)
    assert len(error.value.problems) == 1 and error.value.problems[0].startswith(words)


def test_a_requirement_outside_the_fault_range_is_refused_before_any_run(tmp_path):
    path = write_spec(tmp_path, 0.25, 0)
    text = path.read_text().replace('sweep = ["b0", "b5"]', 'sweep = ["b0", "b5"]\nrequirement = 8e-6')
    path.write_text(text)
    with pytest.raises(LevelSearchError, match=r"requirement: 8 µm is outside the fault's range \(0, 5 µm\]"):
        search(path, Settings(feature=FEATURE, resolution=0.5e-6), run_function=_never, catalog=SYNTHETIC_CATALOG)
    with pytest.raises(LevelSearchError, match="feature: 'nope' is not a feature of the spec"):
        search(path, Settings(feature="nope"), run_function=_never, catalog=SYNTHETIC_CATALOG)


def test_the_probit_fit_recovers_a_known_curve_and_its_crossing():
    """Counts at their expectations under p(x) = Phi(-1.645 + 5e6 x) (a 5 % false-alarm reference and a spread of
    0.2 µm): the maximum-likelihood fit returns the curve, and the power's level is (z(0.95) + 1.645) / 5e6."""
    sizes = np.array([0.0, 0.25e-6, 0.5e-6, 1e-6])
    runs = np.full(4, 1e7)
    fit = probit_fit(sizes, runs * stats.norm.cdf(-1.645 + 5e6 * sizes), runs)
    assert fit == pytest.approx((-1.645, 5e6), rel=1e-4)
    assert probit_level(fit, POWER) == pytest.approx((stats.norm.ppf(POWER) + 1.645) / 5e6, rel=1e-4)
    assert math.isnan(probit_level(None, POWER))


def test_a_preload_loss_sweep_adds_levels_below_the_healthy_preload(tmp_path):
    """A preload sweep from its healthy reference (1000 N): a loss L is the preload 1000 N - L, named by the loss;
    the synthetic feature falls by L / stiffness (2e8 N/m), so the true minimum detectable loss is the closed form
    of the backlash over 5 nm/N, 211 N at sigma = 0.25 µm, and the bounds hold it."""
    path = write_spec(tmp_path, 0.25, 11)
    text = path.read_text().replace('sweep = ["b0", "b5"]', 'sweep = ["p1000", "p0"]\ncondition = "preload"\n'
                                    'reference = "p1000"\nrequirement = 200.0\nrequirement_source = "a test"')
    for old, new in (('"b0"\nconditions = { backlash = 0.0 }', '"p1000"\nconditions = { preload = 1000.0 }'),
                     ('"b5"\nconditions = { backlash = 5e-6 }', '"p0"\nconditions = { preload = 0.0 }')):
        text = text.replace(old, new)
    path.write_text(text)
    result = run_search(path, resolution=100.0)
    assert result.added[0] == "added_loss200N"
    added = {d.name: d for d in result.spec.datasets}["added_loss200N"]
    assert added.conditions == {"preload": 800.0} and added.seeds_from == "p1000"
    low, high = result.last.bounds
    assert low <= true_minimum(0.25) / 5e-9 <= high and result.resolved


def test_the_search_stops_within_its_budgets_and_says_which(tmp_path):
    """A run budget of the fixed sweep, the requirement and one more level (4 x 59 runs), or one level to add: the
    search stops there, the reason named, the runs reported."""
    path = write_spec(tmp_path, 0.25, 5)
    result = run_search(path, resolution=0.1e-6, runs=4 * 59)
    assert result.runs_used == 4 * 59 and result.stop_reason.startswith("run budget: another level of 59 runs")
    assert not result.resolved and "236 runs in all" in statement(result)
    result = run_search(path, resolution=0.1e-6, max_levels=7)  # the fewest the plan check lets through
    assert len(result.added) == 7 and result.stop_reason == "level budget: max_levels = 7 levels added"


def test_invalid_settings_are_one_error_naming_each_field():
    with pytest.raises(LevelSearchError) as error:
        Settings.checked(feature=FEATURE, resolution=-1e-6, method="golden", max_levels=99)
    fields = [p.split(":")[0] for p in error.value.problems]
    assert fields == ["resolution", "method", "max_levels"]
    assert "greater than 0 (got -1e-06)" in error.value.problems[0]


def test_the_command_refuses_a_bad_plan_or_a_used_directory_in_one_line_before_any_run(tmp_path, capsys):
    from app.cli import main
    from tests.cli_helpers import refused_in_one_line

    spec = "campaigns/specs/backlash_bracket.toml"
    assert main(["campaign", "bracket", spec, "--out", str(tmp_path / "a"), "--resolution", "1e-12"]) == 2
    err = capsys.readouterr().err  # the input-error form: one heading, one line per problem, no traceback
    assert "resolution" in err and "finer than the sweep can resolve" in err and "Traceback" not in err, err
    assert not (tmp_path / "a").exists()
    used = tmp_path / "used"
    used.mkdir()
    (used / "spec.json").write_text("{}")
    refused_in_one_line(capsys, ["campaign", "bracket", spec, "--out", str(used)], "holds a campaign already")
    assert sorted(p.name for p in used.iterdir()) == ["spec.json"]  # nothing written there
