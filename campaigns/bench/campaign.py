"""A campaign of the bench twin: the runner (:mod:`campaigns.runner.execution`) with the bench's catalog and run
model unless others are given, and the fidelity audit (:mod:`campaigns.bench.fidelity_audit`) as the stage after
the runs. These are ``campaigns.load_spec`` and ``campaigns.run_campaign``, what the CLI, the service and the
studies call."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from campaigns.bench.adapter import BenchCatalog, simulate_run
from campaigns.bench.fidelity_audit import audit_campaign
from campaigns.runner import execution
from campaigns.runner.catalog import Catalog
from campaigns.runner.files import CampaignInterrupted
from campaigns.runner.runs import RunModel
from campaigns.runner.spec import CampaignSpec, SpecError, read_spec_data, validate_spec
from campaigns.runner.storage import OutputLock
from twin.errors import InputError


def load_spec(path: str | Path, runs: int | None = None, *, timeout: float | None = None,
              catalog: Catalog | None = None) -> CampaignSpec:
    """Read and validate a campaign spec (TOML; :func:`campaigns.runner.spec.read_spec_data` for ``runs`` and
    ``timeout``) against ``catalog``, by default :class:`campaigns.bench.adapter.BenchCatalog` for the spec's
    ``base.parameters`` and ``base.scene``.

    Raises
    ------
    SpecError
        If the file cannot be read or parsed, the bench cannot load the base parameters or scene, or listing every
        validation problem.
    """
    data = read_spec_data(path, runs, timeout=timeout)
    return validate_spec(data, catalog if catalog is not None else _bench_catalog(data))


def _bench_catalog(data: dict) -> BenchCatalog:
    """The bench's catalog for a spec's base; a base the bench cannot load is a spec problem, listed with the
    spec's structural problems."""
    base = data.get("base", {}) if isinstance(data.get("base"), dict) else {}
    try:
        return BenchCatalog(base.get("parameters", "bench"), base.get("scene", "nominal"))
    except InputError as exc:
        structural = []
        try:
            validate_spec(data, None)
        except SpecError as inner:
            structural = inner.problems
        raise SpecError([f"base: {p}" for p in exc.problems] + structural) from None


def run_campaign(
    spec: CampaignSpec | str | Path,
    out_dir: str | Path,
    *,
    workers: int = 2,
    scheduler: str | None = None,
    resume: bool = False,
    progress: bool = True,
    run_function: RunModel | None = None,
    catalog: Catalog | None = None,
    allow_version_mix: bool = False,
    announce: Callable[[str, str], None] | None = None,
) -> Path:
    """Run (or resume) a campaign, then its fidelity audit, and return ``results.nc``.

    ``spec`` is a validated spec or a spec file (validated first with ``catalog``, :func:`load_spec`; nothing runs
    if it is invalid); ``run_function`` the run model (default: the bench twin,
    :data:`campaigns.bench.adapter.simulate_run`). The other options are those of
    :func:`campaigns.runner.execution.run_campaign`; ``announce`` also hears the ``fidelity audit`` stage.
    ``results.nc`` carries the audit in its ``fidelity_audit*`` attributes (its full-fidelity runs in
    ``out_dir/fidelity_audit``).
    """
    if not isinstance(spec, CampaignSpec):
        spec = load_spec(spec, catalog=catalog)
    model = simulate_run if run_function is None else run_function
    options = {"workers": workers, "scheduler": scheduler, "resume": resume, "progress": progress,
               "allow_version_mix": allow_version_mix, "announce": announce}
    results = execution.run_campaign(spec, out_dir, run_function=model, **options)
    try:
        with OutputLock(out_dir):  # results.nc receives the audit's attributes
            audit_campaign(results, spec, model, **options)
    except CampaignInterrupted as exc:  # stopped in the audit: every run of the campaign itself is kept
        total = len(spec.datasets) * spec.runs_per_dataset
        raise CampaignInterrupted(out_dir, total, total, exc.signal_name) from None
    return results
