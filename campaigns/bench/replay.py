"""Replay one run of a finished campaign, alone, with its full time series.

Run ``i`` of data set ``d`` is a function of the stored spec, ``root_seed`` and ``(d, i)``
(:mod:`campaigns.runner.sampling`): :func:`replay_run` re-samples its parameter values from the
resolved distributions stored in ``results.nc``, checks them against the stored values,
rebuilds its request (scene, conditions, solver, the model outputs that fix its fidelity,
its noise stream) and executes it in this process. Its features must equal the stored ones
bit for bit; every signal of the run is kept, undecimated.
"""

from __future__ import annotations

import dataclasses
import importlib
import json
import math
from pathlib import Path

import numpy as np
import xarray as xr

from campaigns.runner.execution import build_request
from campaigns.runner.runs import RunModel, execute
from campaigns.runner.sampling import sample_run
from campaigns.runner.spec import Distribution, SpecError, validate_spec
from campaigns.runner.storage import CampaignError, check_output, read_results, write_netcdf

#: Modules that held a run function before campaigns/ was split into wings: a results.nc written then names
#: its run function (``run_function``) by the old module, which still resolves.
MOVED_RUN_FUNCTION_MODULES = {
    "campaigns.bench": "campaigns.bench.adapter",
    "campaigns.testing": "campaigns.runner.synthetic",
}


def resolve_run_function(name: str) -> RunModel:
    """The run function recorded as ``module:name`` in ``results.nc`` (``run_function`` attribute)."""
    module, sep, attr = name.partition(":")
    module = MOVED_RUN_FUNCTION_MODULES.get(module, module)
    try:
        if not sep:
            raise ImportError(f"{name!r} is not a module:name reference")
        return getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError) as exc:
        raise CampaignError(f"cannot re-create the campaign's run function {name} ({exc}); pass run_function") from exc


def replay_run(results_path: str | Path, dataset: str, run: int, *, out: str | Path | None = None,
               run_function: RunModel | None = None, force: bool = False) -> xr.Dataset:
    """Re-run run ``run`` of data set ``dataset`` of a campaign and compare it with the stored record.

    Parameters
    ----------
    results_path : str or Path
        The campaign's ``results.nc``.
    dataset : str
        Data-set name.
    run : int
        Run index within the data set (zero-based).
    out : str or Path, optional
        Write the replayed run (netCDF) there; refused over an existing file unless ``force``.
    run_function : callable, optional
        Default: the one recorded in ``results.nc`` (``run_function`` attribute), else the bench's.

    Returns
    -------
    xarray.Dataset
        Every signal of the run on ``time`` (undecimated), one scalar per feature, and attributes:
        ``status``, ``parameters`` and ``conditions`` (JSON, SI units), and per feature
        ``stored_<feature>`` and ``identical_<feature>`` (``"yes"``: bit-identical to the stored value).

    Raises
    ------
    CampaignError
        If the file is not a campaign's results, the data set or run does not exist, or the
        re-sampled parameter values differ from the stored ones.
    """
    results_path = Path(results_path)
    if out is not None:
        check_output(out, [results_path], force=force)
    stored = read_results(results_path)
    canonical = json.loads(stored.attrs["spec_json"])
    try:
        spec = validate_spec(canonical["spec"], None)
    except SpecError as exc:
        raise CampaignError(f"{results_path}: its stored spec no longer validates: {exc}") from exc
    names = [str(n) for n in stored["dataset"].values]
    if dataset not in names:
        raise CampaignError(f"{results_path}: no data set {dataset!r}; it has {', '.join(names)}")
    if not (isinstance(run, int) and 0 <= run < spec.runs_per_dataset):
        raise CampaignError(f"{results_path}: run {run!r} out of range; runs are 0..{spec.runs_per_dataset - 1}")
    d = names.index(dataset)
    distributions = [Distribution(**row) for row in canonical["resolved"]]
    targets = [dist.target for dist in distributions]
    values = sample_run(distributions, spec.root_seed, spec.seed_index(d), run, spec.fixed_columns(d, targets),
                        **spec.unit_draws(run, targets))
    recorded = np.array([float(stored[t].values[d, run]) for t in targets])
    if not np.array_equal(values, recorded):
        differ = [t for t, a, b in zip(targets, values, recorded, strict=False) if a != b]
        raise CampaignError(f"{results_path}: re-sampled values of {', '.join(differ)} differ from the stored ones "
                            "(the sampling code changed since the campaign ran); the run cannot be replayed")
    if run_function is None:
        name = stored.attrs.get("run_function", "campaigns.bench.adapter:simulate_run")
        run_function = resolve_run_function(name)
    samples = np.broadcast_to(values, (len(names), spec.runs_per_dataset, len(values)))  # only [d, run] is read
    request = build_request(spec, samples, d, run, targets=targets)
    signals = run_function.signals()
    variables = tuple(signals) if signals is not None else tuple(spec.traces.variables)
    request = dataclasses.replace(request, trace_variables=variables, trace_decimation=1, wall_time_limit=math.inf)
    record = execute(run_function, request)

    replayed = record["trace"].copy() if record["trace"] is not None else xr.Dataset()
    if "time" in replayed.coords and "units" not in replayed["time"].attrs:
        replayed["time"].attrs["units"] = "s"  # the run-function contract: a trace's time is in seconds
    for name, variable in replayed.variables.items():  # described for CF tools, even when the model did not
        if "long_name" not in variable.attrs and "standard_name" not in variable.attrs:
            variable.attrs["long_name"] = str(name).replace("_", " ")
    attrs = {
        "title": f"Replay of run {run} of data set {dataset} of campaign {spec.name}",
        "source": f"campaigns.bench.replay of {results_path}",
        "campaign": spec.name, "dataset": dataset, "run": run, "root_seed": str(spec.root_seed),
        "status": record["status"], "failure_reason": record["failure_reason"],
        "stored_status": str(stored["status"].values[d, run]),
        "parameters": json.dumps(request.parameter_values, sort_keys=True),
        "conditions": json.dumps(request.conditions, sort_keys=True),
    }
    for feature in spec.features:
        value, kept = record["features"][feature], float(stored[feature].values[d, run])
        unit, long_name = stored[feature].attrs.get("units", ""), stored[feature].attrs.get("long_name", feature)
        replayed[feature] = ((), value, {"units": unit, "long_name": long_name})
        attrs[f"stored_{feature}"] = kept
        attrs[f"identical_{feature}"] = "yes" if np.float64(value).tobytes() == np.float64(kept).tobytes() else "no"
    replayed.attrs.update(attrs)
    if out is not None:
        write_netcdf(replayed, out, title=attrs["title"],
                     history=f"run {run} of data set {dataset} replayed from {results_path} (campaigns.bench.replay)")
    return replayed
