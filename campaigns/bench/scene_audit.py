"""``twin fidelity audit``: the fidelity audit of one scene, as a small campaign of its own.

It runs a campaign (:func:`campaigns.bench.campaign.run_campaign`), whose last stage is the audit
(:func:`campaigns.bench.fidelity_audit.audit_campaign`), so it sits above both.
"""

from __future__ import annotations

from pathlib import Path

import xarray as xr

from campaigns.bench.campaign import load_spec, run_campaign
from campaigns.bench.fidelity_audit import AUDIT_MIN_PAIRS
from campaigns.runner.spec import Dataset, FidelityAudit, Observability, Traces
from twin.errors import InputError
from twin.scenes import load_scene

#: The default spec of ``twin fidelity audit``: the thesis study's uncertainty table, seed, features and solver.
THESIS_SPEC = Path(__file__).parents[1] / "specs" / "thesis_backlash.toml"


def audit_scene(scene: str, out_dir: str | Path, runs: int = 50, spec_path: str | Path | None = None,
                workers: int = 2) -> xr.Dataset:
    """``twin fidelity audit``: ``runs`` sampled runs of one scene, auto against full fidelity.

    The uncertainty table, seed, features and solver come from ``spec_path`` (default: the
    thesis study, ``campaigns/specs/thesis_backlash.toml``); the scene is the only data set.
    """
    problems = [] if isinstance(runs, int) and runs >= AUDIT_MIN_PAIRS else [
        f"runs: {runs!r} must be an integer >= {AUDIT_MIN_PAIRS} (the fewest paired runs an audit verdict needs)"]
    try:
        load_scene(scene)
    except InputError as exc:
        problems += exc.problems
    if problems:
        raise InputError("fidelity audit", problems)
    spec = load_spec(spec_path or THESIS_SPEC)
    name = Path(scene).stem  # a scene file's data set is named after the file, as the CLI's output directory
    spec = spec.model_copy(update={
        "name": f"fidelity_audit_{name}",
        "datasets": [Dataset(name=name, scene=scene)],
        "runs_per_dataset": runs,
        "traces": Traces(),
        "observability": Observability(),
        "fidelity_audit": FidelityAudit(runs=runs),
        "solver": spec.solver.model_copy(update={"fidelity": "auto"}),
    })
    results = run_campaign(spec, out_dir, workers=workers, progress=False)
    with xr.open_dataset(Path(results).parent / "fidelity_audit" / "fidelity_audit.nc") as handle:
        audit = handle.load()
    with xr.open_dataset(results) as handle:
        audit.attrs["fidelity_auto"] = handle.attrs.get(f"fidelity_{name}", "")
        audit.attrs["summary"] = "\n".join(f"{k}: {v}" for k, v in handle.attrs.items()
                                           if k.startswith("fidelity_audit"))
    return audit
