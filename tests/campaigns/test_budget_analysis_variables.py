"""The disk estimate's count of analysis.nc variables (issue 40: it was one constant while the analysis writes a set
per fault sweep): :func:`campaigns.runner.budget.analysis_variables` is at least what the analysis writes, for the
thesis study (one sweep) and the demo (two).

What the analysis writes is counted on the file it writes for results shaped like the spec's (its data sets,
features, conditions, the bench's margin figures, its stored spec): the variables do not depend on the feature values,
so synthetic numbers stand in for the runs (4 per data set, as ``twin campaign run --runs 4``).
"""

from __future__ import annotations

from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

import campaigns
from campaigns.analysis.campaign_analysis import analysis_dataset
from campaigns.bench.adapter import MARGIN_VARIABLES
from campaigns.runner.budget import SWEEP_VARIABLES, analysis_variables
from campaigns.runner.files import cf_encoding

SPECS = Path(__file__).parents[2] / "campaigns" / "specs"
RUNS = 4


def _results_like(spec: campaigns.CampaignSpec) -> xr.Dataset:
    """Results of ``spec``'s shape, every run ok, features and margins drawn at random."""
    rng = np.random.default_rng(0)
    names = [d.name for d in spec.datasets]
    shape = (len(names), RUNS)
    dims = ("dataset", "run")
    conditions = sorted({c for d in spec.datasets for c in d.conditions})
    variables = {
        **{f: (dims, rng.normal(size=shape), {"role": "feature", "units": "m"}) for f in spec.features},
        **{u.target: (dims, rng.normal(size=shape), {"role": "sampled", "units": "1"}) for u in spec.uncertainties},
        **{m: (dims, rng.uniform(1, 2, shape), {"role": "margin", "units": "1", "loop": loop, "metric": metric})
           for m, (loop, metric) in MARGIN_VARIABLES.items()},
        **{f"condition_{c}": ("dataset", [float(d.conditions.get(c, 0.0)) for d in spec.datasets]) for c in conditions},
        "status": (dims, np.full(shape, "ok", dtype=object)),
        "failure_reason": (dims, np.full(shape, "", dtype=object)),
        "wall_time": (dims, np.ones(shape)),
    }
    return xr.Dataset(variables, coords={"dataset": names, "run": np.arange(RUNS)},
                      attrs={"spec_json": spec.to_json(), "spec_hash": spec.spec_hash()})


def written_variables(spec: campaigns.CampaignSpec, tmp_path: Path) -> int:
    """The netCDF variables of the analysis.nc written for results of ``spec``'s shape."""
    analysis = analysis_dataset(_results_like(spec), n_boot=10, sensitivity_boot=5)
    path = tmp_path / f"{spec.name}.nc"
    analysis.to_netcdf(path, engine="netcdf4", encoding=cf_encoding(analysis))
    with netCDF4.Dataset(path) as written:
        return len(written.variables)


@pytest.fixture(scope="module")
def counts(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("analysis")
    specs = {name: campaigns.load_spec(SPECS / f"{name}.toml", RUNS) for name in ("thesis_backlash", "demo")}
    return {name: (spec, written_variables(spec, tmp)) for name, spec in specs.items()}


@pytest.mark.parametrize("name", ["thesis_backlash", "demo"])
def test_the_estimate_counts_at_least_the_variables_written(counts, name):
    spec, written = counts[name]
    assert analysis_variables(spec) >= written


def test_a_further_sweep_adds_its_own_set(counts):
    """The demo is the thesis study with a second sweep (and more data sets, which the variables do not count): the
    difference is one sweep's set, as the estimate adds it."""
    (thesis, one), (demo, two) = counts["thesis_backlash"], counts["demo"]
    assert (len(thesis.further_sweeps), len(demo.further_sweeps)) == (0, 1)
    assert two - one == SWEEP_VARIABLES == analysis_variables(demo) - analysis_variables(thesis)

