"""Spec validation: every error at once with its path, nothing submitted; range conventions."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from campaign_helpers import SYNTHETIC_SPEC, load, write_spec

import campaigns
from campaigns.runner.spec import SpecError
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, SyntheticModel
from campaigns.units import HALF_RANGE_SIGMAS

SPECS = Path(campaigns.__file__).parent / "specs"

BAD = """
name = "bad"
root_seed = -1
runs_per_dataset = 0
features = ["backlash_feature", "no_such_feature"]

[base]
scene = "no_such_scene"

[[datasets]]
name = "ds2"
conditions = { backlash = nan, wind = 3.0 }

[[uncertainties]]
target = "synthetic.gain"
distribution = "gaussian"
sigma = -0.1

[[uncertainties]]
target = "synthetic.offset"
distribution = "uniform"
low = 2.0
high = 1.0
unit = "um"

[[uncertainties]]
target = "synthetic.no_such_parameter"
distribution = "constant"

[[uncertainties]]
target = "synthetic.stiffness"
distribution = "uniform"
half_range = 3.0
unit = "um"

[[uncertainties]]
target = "synthetic.inert"
distribution = "gaussian"
mean = nan
sigma = 1.0
"""

EXPECTED = [
    "root_seed:",
    "runs_per_dataset:",
    "features: unknown feature(s) no_such_feature",
    "base.scene: unknown scene 'no_such_scene'",
    "datasets[0].conditions.backlash:",
    "datasets[0].conditions.wind: unknown condition wind",
    "uncertainties[0].sigma:",
    "uncertainties[1]: low (2) > high (1)",
    "uncertainties[2]: unknown parameter 'synthetic.no_such_parameter'",
    "uncertainties[3]: synthetic.stiffness: unit 'um' does not convert to 'N/m'",
    "uncertainties[4].mean:",
]


def test_a_bad_spec_reports_every_problem_and_runs_nothing(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(BAD)
    log = tmp_path / "log"
    log.mkdir()
    with pytest.raises(SpecError) as info:
        campaigns.run_campaign(path, tmp_path / "out", catalog=SYNTHETIC_CATALOG, progress=False,
                               run_function=SyntheticModel(log_dir=str(log)))
    problems = info.value.problems
    for expected in EXPECTED:
        assert any(p.startswith(expected) for p in problems), f"{expected!r} not in {problems}"
    assert len(problems) == len(EXPECTED)
    assert not list(log.iterdir())  # the run function was never called
    assert not (tmp_path / "out").exists()  # nothing was submitted or written


@pytest.mark.parametrize(
    "text, expected",
    [
        ("[execution]\ntimeout = -1.0\n", "execution.timeout:"),
        ("[observability]\nsweep = [\"ds2\", \"ds5\", \"nope\"]\n", "observability.sweep: unknown data set(s) nope"),
        ("[observability]\nsweep = [\"ds2\", \"ds6\"]\n",
         "observability.sweep: needs exactly one zero-backlash reference"),
        ("[[uncertainties]]\ntarget = \"synthetic.gain\"\ndistribution = \"constant\"\n",
         "uncertainties: target(s) listed twice: synthetic.gain"),
        ("[[uncertainties]]\ntarget = \"synthetic.inert\"\ndistribution = \"lognormal\"\nhalf_range = 5.0\n",
         "uncertainties[6]: a lognormal needs relative = true"),
        ("[[uncertainties]]\ntarget = \"synthetic.offset\"\ndistribution = \"gaussian\"\n"
         "relative = true\nhalf_range = 5.0\n",
         "uncertainties[6]: relative range on synthetic.offset whose nominal value is 0"),
        ("unknown_key = 1\n", "unknown_key:"),
    ],
)
def test_single_problems_are_named_with_their_path(tmp_path, text, expected):
    with pytest.raises(SpecError) as info:
        load(write_spec(tmp_path, text, append=text.startswith("[[")))
    assert any(p.startswith(expected) for p in info.value.problems), info.value.problems


def test_unparsable_file_is_a_spec_error(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("name = ")
    with pytest.raises(SpecError, match="broken.toml"):
        load(path)


def test_ranges_resolve_to_si_with_the_half_range_convention():
    spec = load(SYNTHETIC_SPEC)
    d = {x.target: x for x in spec.distributions()}
    gain = d["synthetic.gain"]  # ±10 %Nom, G
    assert gain.mean == 1.0 and gain.sigma == pytest.approx(0.1 / HALF_RANGE_SIGMAS)
    offset = d["synthetic.offset"]  # -1..1 um, U
    assert (offset.low, offset.high, offset.unit) == (pytest.approx(-1e-6), pytest.approx(1e-6), "m")
    stiffness = d["synthetic.stiffness"]  # ±20 %Nom, truncated G
    assert (stiffness.low, stiffness.high) == (pytest.approx(1.6e8), pytest.approx(2.4e8))
    assert stiffness.sigma == pytest.approx(0.4e8 / HALF_RANGE_SIGMAS)
    inert = d["synthetic.inert"]  # lognormal ±50 %: the median x 1.5 sits at +3 sigma of the log
    assert inert.mean == 3.0 and inert.sigma * HALF_RANGE_SIGMAS == pytest.approx(math.log(1.5))
    temperature = d["scene.room_temperature"]  # 15..35 degC
    assert (temperature.low, temperature.high, temperature.unit) == (pytest.approx(288.15), pytest.approx(308.15), "K")
    pressure = d["scene.supply_pressure"]  # -10..0 %Nom of the scene's nominal
    assert (pressure.low, pressure.high) == (pytest.approx(5.4e5), pytest.approx(6e5))


def test_runs_override_and_extends(tmp_path):
    spec = load(write_spec(tmp_path, 'name = "child"\n[execution]\ntimeout = 2.0\n'), runs=3)
    parent = load(SYNTHETIC_SPEC)
    assert spec.runs_per_dataset == 3 and spec.name == "child"
    assert spec.execution.timeout == 2.0 and spec.execution.isolation == parent.execution.isolation  # table merged
    assert spec.spec_hash() != parent.spec_hash()


def test_shipped_specs_validate_structurally():
    """Structure only, without the catalog (the rows against the bench: test_table_9_5_extension_specs.py)."""
    # the demo: the thesis's 7 data sets, then 0.5, 1 and 2 um levels at and around the backlash requirement and
    # 900, 800 and 600 N preloads at and around the preload-loss one, each a sweep of its own (issue 42)
    for name, datasets, sweeps in (("thesis_backlash.toml", 7, [["ds4", "ds6", "ds7", "ds2"]]),
                                   ("demo.toml", 13, [["ds4", "b0_5", "b1", "b2", "ds6", "ds7", "ds2"],
                                                      ["ds5", "p900", "p800", "p600"]])):
        data = campaigns.runner.spec.read_spec(SPECS / name)
        spec = campaigns.runner.spec.validate_spec(data, None)
        assert len(spec.datasets) == datasets
        assert len(spec.uncertainties) == 38 + 10  # every row of Table 9.5, then the 10 rows of its extension
        assert [s.sweep for s in spec.sweeps] == sweeps
    assert campaigns.runner.spec.validate_spec(
        campaigns.runner.spec.read_spec(SPECS / "thesis_backlash.toml"), None).runs_per_dataset == 1000
