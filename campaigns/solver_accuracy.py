"""Campaign-level accuracy of a solver configuration (the speed-versus-accuracy study, issue 7).

A solver configuration is good enough for campaigns when the feature distribution it
produces cannot be told from the one of a much finer reference over the same sampled runs:
the shift of the mean and of the standard deviation, and the Kolmogorov-Smirnov distance,
are compared with the Monte Carlo sampling error of the mean, ``1.96 sigma / sqrt(N)``.
Both configurations run the same spec with the same seeds, so the comparison is paired:
run i of a data set has the same parameters and the same noise under both.
"""

from __future__ import annotations

from pathlib import Path

import xarray as xr

from campaigns.comparison import compare_features
from campaigns.execution import run_campaign
from campaigns.spec import CampaignSpec, Observability, Solver, Traces, load_spec

REFERENCE = ("rk4", 7.8125e-6)  # a quarter of the finest candidate step: converged to < 1e-6 um (docs/accuracy.md)
CANDIDATES = (("rk4", 6.25e-5), ("rk4", 3.125e-5), ("semi_implicit_euler", 3.125e-5))


def variant(spec: CampaignSpec, integrator: str, dt: float, datasets: tuple[str, ...], runs: int) -> CampaignSpec:
    """The spec restricted to ``datasets`` and ``runs``, solved with ``integrator`` at ``dt``, no traces."""
    chosen = [d for d in spec.datasets if d.name in datasets]
    return spec.model_copy(update={
        "name": f"{spec.name}_{integrator}_{dt:.4g}",
        "datasets": chosen,
        "runs_per_dataset": runs,
        "solver": Solver(integrator=integrator, dt=dt),
        "traces": Traces(),
        "observability": Observability(),
    })


def campaign_accuracy(out_dir: str | Path, spec_path: str | Path = "campaigns/specs/demo.toml",
                      datasets: tuple[str, ...] = ("ds2", "ds5"), runs: int = 100, candidates=CANDIDATES,
                      reference=REFERENCE, workers: int = 2) -> xr.Dataset:
    """Run the reference and every candidate over the same sampled runs; return the comparison.

    Returns
    -------
    xarray.Dataset
        Dimensions ``candidate`` x ``dataset``: the :func:`compare_features` variables and
        the candidates' total wall time.
    """
    out = Path(out_dir)
    spec = load_spec(spec_path)
    results = {}
    for integrator, dt in (reference, *candidates):
        run_spec = variant(spec, integrator, dt, datasets, runs)
        results[(integrator, dt)] = xr.load_dataset(run_campaign(run_spec, out / run_spec.name, workers=workers,
                                                                 progress=False))
    reference_results = results[reference]
    comparisons = []
    for integrator, dt in candidates:
        comparison = compare_features(results[(integrator, dt)], reference_results)
        comparison["wall_time"] = results[(integrator, dt)].wall_time.sum()
        comparisons.append(comparison.expand_dims(candidate=[f"{integrator} dt={dt:g}"]))
    combined = xr.concat(comparisons, dim="candidate")
    combined.attrs.update(reference=f"{reference[0]} dt={reference[1]:g}", runs=runs, spec=str(spec_path),
                          reference_wall_time=float(reference_results.wall_time.sum()))
    combined.to_netcdf(out / "campaign_accuracy.nc", engine="netcdf4")
    return combined
