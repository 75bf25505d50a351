"""Fidelity audit: the automatic fidelity against the full model, over the same sampled runs.

A campaign runs at ``fidelity = "auto"`` by default: each subsystem of the twin at the
cheapest level its scene and outputs allow (``twin.fidelity``). The audit re-runs the
first ``N`` runs of every data set at full fidelity, with the same parameters and the
same noise (run ``i`` of data set ``d`` has the same seeds in both), and compares the
features: paired mean shift and largest paired difference against the Monte Carlo
sampling error of the mean, ``1.96 sigma / sqrt(N)``, and the two-sample KS test.

A data set *passes* when every feature's mean shift is below :data:`MEAN_SHIFT_TOLERANCE`
and the KS test does not reject at :data:`KS_LEVEL`. Failing is a result, not an error:
it is recorded in ``results.nc`` (``fidelity_audit*`` attributes) and shown by the report,
and the rule that chose the level must be fixed (``twin/fidelity/rules.toml``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from campaigns.comparison import compare_features
from campaigns.spec import CampaignSpec, FidelityAudit, Observability, Traces
from campaigns.storage import atomic_write

MEAN_SHIFT_TOLERANCE = 1.0e-7  # m: 0.1 um, a tenth of the 1 um backlash the bench must detect (Table 9.3)
KS_LEVEL = 0.05


def full_fidelity_variant(spec: CampaignSpec, runs: int) -> CampaignSpec:
    """The spec's first ``runs`` runs of every data set at full fidelity, without traces or audit."""
    return spec.model_copy(update={
        "name": f"{spec.name}_full_fidelity",
        "runs_per_dataset": runs,
        "solver": spec.solver.model_copy(update={"fidelity": "full"}),
        "traces": Traces(),
        "observability": Observability(),
        "fidelity_audit": FidelityAudit(runs=0),
    })


def compare_fidelity(auto: xr.Dataset, full: xr.Dataset, features: list[str]) -> xr.Dataset:
    """Per data set and feature: the :func:`campaigns.comparison.compare_features` figures of the
    auto runs against their full-fidelity twins, the verdict, and the wall-time speedup."""
    runs = full.sizes["run"]
    paired = auto.isel(run=slice(0, runs))
    per_feature = [compare_features(paired, full, f).expand_dims(feature=[f]) for f in features]
    audit = xr.concat(per_feature, dim="feature")
    audit["passed"] = (np.abs(audit.mean_shift) < MEAN_SHIFT_TOLERANCE) & (audit.ks_pvalue >= KS_LEVEL)
    both = (paired.status == "ok") & (full.status == "ok")
    audit["speedup"] = full.wall_time.where(both).sum("run") / paired.wall_time.where(both).sum("run")
    audit["speedup"].attrs["long_name"] = "full-fidelity wall time / auto wall time over the paired runs"
    audit.attrs.update(runs=runs, mean_shift_tolerance=MEAN_SHIFT_TOLERANCE, ks_level=KS_LEVEL)
    return audit


def summary_attrs(audit: xr.Dataset) -> dict[str, str]:
    """``fidelity_audit*`` attributes for ``results.nc`` (what the report's Fidelity section shows)."""
    attrs = {"fidelity_audit_runs": str(audit.attrs["runs"])}
    flagged = []
    for name in audit.dataset.values:
        lines = []
        for feature in audit.feature.values:
            row = audit.sel(dataset=name, feature=feature)
            verdict = "pass" if bool(row.passed) else "FLAGGED"
            lines.append(f"{feature}: mean shift {float(row.mean_shift) * 1e6:+.4f} um, max paired "
                         f"{float(row.max_paired_difference) * 1e6:.4f} um, MC error "
                         f"{float(row.sampling_error) * 1e6:.4f} um, "
                         f"KS p {float(row.ks_pvalue):.2f} -> {verdict}")
            if not bool(row.passed):
                flagged.append(f"{name}/{feature}")
        speedup = float(audit.speedup.sel(dataset=name))
        attrs[f"fidelity_audit_{name}"] = f"speedup x{speedup:.2f}; " + "; ".join(lines)
    attrs["fidelity_audit"] = ("passed: auto is indistinguishable from full fidelity on every data set"
                               if not flagged else f"FLAGGED (rule to fix): {', '.join(flagged)}")
    return attrs


def audit_campaign(results_path: Path, spec: CampaignSpec, run_campaign_function, **run_options) -> xr.Dataset | None:
    """Run the full-fidelity twin of the campaign's first runs, compare, and record the audit in
    ``results.nc``. Returns the audit (also written as ``fidelity_audit.nc``), or None when there is
    nothing to audit (audit off, full fidelity already, or a model that reports no fidelity)."""
    with xr.open_dataset(results_path) as handle:
        auto = handle.load()
    reported = any(k.startswith("fidelity_") and k != "fidelity_requested" for k in auto.attrs)
    runs = min(spec.fidelity_audit.runs, spec.runs_per_dataset)
    if runs < 2 or spec.solver.fidelity == "full" or not reported:
        why = ("the campaign runs at full fidelity" if spec.solver.fidelity == "full"
               else "the run function reports no fidelity" if not reported
               else f"fidelity_audit.runs = {spec.fidelity_audit.runs} with {spec.runs_per_dataset} run(s) "
                    "per data set; it needs 2 or more")
        _write_attrs(results_path, auto, {"fidelity_audit": f"not run ({why})"})
        return None
    out_dir = results_path.parent / "fidelity_audit"
    full_path = run_campaign_function(full_fidelity_variant(spec, runs), out_dir, **run_options)
    with xr.open_dataset(full_path) as handle:
        full = handle.load()
    audit = compare_fidelity(auto, full, list(spec.features))
    atomic_write(out_dir / "fidelity_audit.nc", lambda tmp: audit.to_netcdf(tmp, engine="netcdf4"))
    _write_attrs(results_path, auto, summary_attrs(audit))
    return audit


def _write_attrs(path: Path, results: xr.Dataset, attrs: dict[str, str]) -> None:
    results.attrs.update(attrs)
    atomic_write(path, lambda tmp: results.to_netcdf(tmp, engine="netcdf4"))
