"""A campaign of the bench twin: the runner (:mod:`campaigns.runner.execution`) with the bench's catalog and run
model unless others are given, one fidelity per fault sweep (:func:`sweep_fidelity`), and the fidelity audit
(:mod:`campaigns.bench.fidelity_audit`) as the stage after the runs. These are ``campaigns.load_spec`` and
``campaigns.run_campaign``, what the CLI, the service and the studies call."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import twin
from campaigns.bench.adapter import BenchCatalog, simulate_run
from campaigns.bench.fidelity_audit import audit_campaign, audit_problems
from campaigns.runner import execution
from campaigns.runner.catalog import Catalog
from campaigns.runner.files import CampaignInterrupted
from campaigns.runner.runs import RunModel
from campaigns.runner.spec import CampaignSpec, SpecError, read_spec_data, validate_spec
from campaigns.runner.storage import OutputLock
from twin.errors import InputError
from twin.fidelity import SUBSYSTEMS, resolve_fidelity


def load_spec(path: str | Path, runs: int | None = None, *, timeout: float | None = None,
              catalog: Catalog | None = None) -> CampaignSpec:
    """Read and validate a campaign spec (TOML; :func:`campaigns.runner.spec.read_spec_data` for ``runs`` and
    ``timeout``) against ``catalog``, by default :class:`campaigns.bench.adapter.BenchCatalog` for the spec's
    ``base.parameters`` and ``base.scene``.

    Raises
    ------
    SpecError
        If the file cannot be read or parsed, the bench cannot load the base parameters or scene, or listing every
        validation problem (the fidelity audit's settings too: :func:`campaigns.bench.fidelity_audit.audit_problems`).
    """
    data = read_spec_data(path, runs, timeout=timeout)
    spec = validate_spec(data, catalog if catalog is not None else _bench_catalog(data))
    _check_audit(spec)
    return spec


def _check_audit(spec: CampaignSpec) -> None:
    """Refuse, before any run, audit settings the audit cannot judge with (one :class:`SpecError`)."""
    problems = audit_problems(spec)
    if problems:
        raise SpecError(problems)


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


def _nominal_run(spec: CampaignSpec, index: int):
    """Data set ``index``'s scene (its procedure and conditions) and the nominal parameters with its fixed ones: the
    run's scene, as :func:`campaigns.bench.adapter.run_scene` builds it."""
    dataset = spec.datasets[index]
    scene = (twin.load_scene(dataset.scene or spec.base.scene).with_procedure(dataset.procedure)
             .with_conditions(dataset.conditions))
    return scene, twin.load_parameters(spec.base.parameters).with_values(dataset.parameters)


def _automatic_levels(spec: CampaignSpec, index: int) -> dict[str, str]:
    """The levels ``twin.simulate`` chooses for data set ``index`` (:func:`_nominal_run`) from the spec's fidelity
    request, for the outputs every run of the campaign produces."""
    outputs = list(spec.features) + (list(spec.traces.variables) if spec.traces.runs_per_dataset else [])
    return dict(resolve_fidelity(*_nominal_run(spec, index), spec.solver.fidelity, outputs).levels)


def _full_levels(members: list[int], chosen: dict[int, dict[str, str]]) -> dict[str, str]:
    """Every subsystem at its most detailed level; the pneumatics at the most detailed any of ``members`` takes (a
    detached cylinder is a condition of the test, not a simplification)."""
    pneumatics = min((chosen[k]["pneumatics"] for k in members), key=SUBSYSTEMS["pneumatics"].level_names.index)
    return {name: SUBSYSTEMS[name].full for name in SUBSYSTEMS} | {"pneumatics": pneumatics}


def measured_fidelity(spec: CampaignSpec) -> CampaignSpec:
    """The spec with the full model on every data set whose automatic levels are not those the speed measurement
    covers (issue 42, item 3: the automatic level simplifies only where it is measurably faster and passes its audit).

    ``twin/fidelity/speed.toml`` holds, per scene, the speedup of the levels the rules choose for the scene's own
    outputs, and the audits behind the rules judged those outputs. A campaign that asks for other outputs (the demo's
    drag torque on data set 1: the torque meter's refresh is then modelled, not ideal) gets other levels, which no
    measurement covers: such a data set runs the full model (its ``fidelity``, recorded in ``results.nc`` with the
    spec). On data set 1 of the demo the audit could not show those levels within the tolerances either: at all its
    59 paired runs the drag torque's sd ratio stayed undetermined (docs/fidelity.md, "What the audit re-runs"). A
    spec at ``"full"``, with a named level set or without such a data set is returned unchanged (its results and hash
    stay as they were); a data set that already names its levels keeps them.
    """
    if spec.solver.fidelity != "auto":
        return spec
    datasets = list(spec.datasets)
    for k, dataset in enumerate(spec.datasets):
        if dataset.fidelity is not None:
            continue
        measured = dict(resolve_fidelity(*_nominal_run(spec, k), "auto").levels)  # the scene's own outputs
        used = _automatic_levels(spec, k)
        full = _full_levels([k], {k: used})
        if used != measured and used != full:
            datasets[k] = dataset.model_copy(update={"fidelity": full})
    return spec.model_copy(update={"datasets": datasets}) if datasets != list(spec.datasets) else spec


def _sweep_groups(spec: CampaignSpec) -> list[list[int]]:
    """The data sets of each fault sweep (indices), sweeps that share a data set joined into one group: a data set
    runs one model, so all the sweeps it belongs to share it."""
    names = [d.name for d in spec.datasets]
    groups: list[set[int]] = []
    for observability in spec.sweeps:
        members = {names.index(n) for n in observability.sweep}
        for joined in [g for g in groups if g & members]:
            members |= joined
            groups.remove(joined)
        groups.append(members)
    return [sorted(g) for g in groups]


def sweep_fidelity(spec: CampaignSpec) -> CampaignSpec:
    """The spec with one set of fidelity levels across each fault sweep (issue 42, item 3).

    The automatic choice follows each data set's conditions, so along a sweep it may switch a subsystem's model
    between levels (the quasi-static screw axial at 1000 N preload only, ``min_preload`` in
    ``twin/fidelity/rules.toml``), and that switch alone moves the feature the sweep reads (on data set 5 the true
    drag torque by about what 13 N of preload loss does): the detection curve would then mix a model change with the
    fault. Where the members' automatic choices differ, the sweep runs the full model (per subsystem its most detailed
    level; the pneumatics at the most detailed any member takes, since a detached cylinder is a condition, not a
    simplification): a mixture of the members' levels is a model no speed measurement covers
    (``twin/fidelity/speed.toml`` holds each scene's own choice), and on the preload sweep such a mixture, the dynamic
    shaft with the ideal current loop, steps at 62.5 us like the full model and so buys nothing (docs/fidelity.md,
    "Fidelity that pays"). The members whose own choice differs run at it (their ``fidelity``, recorded in
    ``results.nc`` with the spec). A spec without a sweep, one that asks for ``"full"``, and a sweep whose members
    already agree are returned unchanged, so their results and hash stay as they were.
    """
    if spec.solver.fidelity == "full" or not spec.sweeps:
        return spec
    datasets = list(spec.datasets)
    for members in _sweep_groups(spec):
        chosen = {k: _automatic_levels(spec, k) for k in members}
        if all(chosen[k] == chosen[members[0]] for k in members):
            continue
        common = _full_levels(members, chosen)
        for k in members:
            if chosen[k] != common:
                datasets[k] = datasets[k].model_copy(update={"fidelity": common})
    return spec.model_copy(update={"datasets": datasets}) if datasets != list(spec.datasets) else spec


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
    :func:`campaigns.runner.execution.run_campaign`; ``announce`` also hears the ``fidelity audit`` stage. The bench
    twin runs the automatic levels only where they are those its speed measurement covers (:func:`measured_fidelity`)
    and each fault sweep at one set of fidelity levels (:func:`sweep_fidelity`). The runs and the audit share
    one cluster (:class:`campaigns.runner.execution.Cluster`); audit settings it cannot judge with are refused before
    anything runs.
    ``results.nc`` carries the audit in its ``fidelity_audit*`` attributes (its full-fidelity runs in
    ``out_dir/fidelity_audit``).
    """
    if not isinstance(spec, CampaignSpec):
        spec = load_spec(spec, catalog=catalog)
    _check_audit(spec)
    if run_function is None:  # the bench twin's automatic fidelity: measured levels only, one model along each sweep
        spec = sweep_fidelity(measured_fidelity(spec))
    model = simulate_run if run_function is None else run_function
    # one cluster for the runs and the audit: the audit's runs go to the workers that hold the compiled model
    with execution.Cluster(workers, scheduler, announce) as cluster:
        options = {"workers": workers, "scheduler": scheduler, "resume": resume, "progress": progress,
                   "allow_version_mix": allow_version_mix, "announce": announce, "cluster": cluster}
        results = execution.run_campaign(spec, out_dir, run_function=model, **options)
        try:
            with OutputLock(out_dir):  # results.nc receives the audit's attributes
                audit_campaign(results, spec, model, **options)
        except CampaignInterrupted as exc:  # stopped in the audit: every run of the campaign itself is kept
            total = len(spec.datasets) * spec.runs_per_dataset
            raise CampaignInterrupted(out_dir, total, total, exc.signal_name) from None
    return results
