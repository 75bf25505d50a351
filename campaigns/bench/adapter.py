"""The bench twin as a campaign model: its catalog and its run model (:data:`simulate_run`).

The campaign machinery (spec, sampling, runs, execution, storage, analysis) is a general
runner; this module is where it meets the bench twin. The synthetic test model
(:mod:`campaigns.runner.synthetic`) runs without it.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

import twin
from campaigns.runner.catalog import CONDITION_UNITS, condition_units, lookup_nominal
from campaigns.runner.runs import RunRequest
from twin.control.margins import LOOPS, METRICS, loop_margins
from twin.engine.model import load_system_parameters
from twin.errors import InputError
from twin.features import FEATURES
from twin.layout import OUTPUT_NAMES
from twin.scenes import CONDITIONS, split_targets
from twin.scenes.profiles import profile_values
from twin.solver import DEFAULT_DT, DEFAULT_LANES, solver_label, split_solver

#: Features the bench computes (``twin.simulate`` scalar outputs), with unit and long name: the
#: declarations of :mod:`twin.features` (a light module: no numba compilation on import).
BENCH_FEATURES: dict[str, tuple[str, str]] = {name: (f.unit, f.long_name) for name, f in FEATURES.items()}


def scene_conditions(scene) -> dict[str, float]:
    """Numeric conditions of a scene (``scene.conditions``) that campaigns know units for."""
    return {k: float(v) for k, v in scene.conditions.items() if k in CONDITION_UNITS}


def dataset_conditions(spec) -> tuple[dict, dict]:
    """Every condition of each data set's effective scene, for ``results.attrs["dataset_conditions"]``.

    Takes all conditions the scene holds (numbers in SI with the unit of
    ``twin.scenes.CONDITIONS``, strings as they are), after the data set's overrides, plus
    ``external_force_peak`` [N], the largest |force demand| of the scene. Returns
    ``({dataset: {condition: {"value", "unit"}}}, the base scene's conditions in the same form)``.
    """
    def described(scene) -> dict:
        entries = {k: {"value": float(v) if isinstance(v, (int, float)) else str(v),
                       "unit": CONDITIONS[k][0] if k in CONDITIONS and isinstance(v, (int, float)) else ""}
                   for k, v in scene.conditions.items()}
        entries["external_force_peak"] = {"value": force_demand_peak(scene), "unit": "N"}
        return entries

    datasets = {d.name: described(_scene(d.scene or spec.base.scene).with_procedure(d.procedure)
                          .with_conditions(dict(d.conditions)))
                for d in spec.datasets}
    return datasets, described(_scene(spec.base.scene))


def force_demand_peak(scene) -> float:
    """The largest |force demand| of a scene [N], on 2001 instants over its duration."""


    times = np.linspace(0.0, scene.duration, 2001)
    return float(np.max(np.abs(profile_values(scene.force_table(), times))))


#: Per-run loop margins stored in ``results.nc`` (role "margin"): ``{variable: (loop, metric)}``
#: for every loop and figure of :mod:`twin.control.margins`.
MARGIN_VARIABLES = {f"{loop}_loop_{metric}": (loop, metric) for loop in LOOPS for metric in METRICS}
#: Variable holding why a run's margins are NaN (empty when all present loops were computed).
MARGIN_NOTE = "loop_margins_note"


def run_margins(request: RunRequest) -> tuple[dict[str, float], str]:
    """Loop margins of one run's parameter set (:func:`twin.control.margins.loop_margins`).

    The run's parameters and scene conditions as :func:`simulate_one` builds them; the force loop
    only when the scene's cylinder is attached, linearised at the scene's peak force demand (the force
    it holds) with the scene's supply pressure and air temperature. Never raises: a loop that cannot be
    computed is NaN and the second return value says why (a property of the parameters, so a failed run
    gets its margins too).

    Returns
    -------
    (dict, str)
        ``{variable of MARGIN_VARIABLES: value}`` and the note (empty when every present loop was computed).
    """
    values = dict.fromkeys(MARGIN_VARIABLES, math.nan)
    notes = []
    try:
        scene = run_scene(request)
        p = _parameters(request.parameters).with_values(request.parameter_values).values()
    except Exception as exc:  # noqa: BLE001 - a bad parameter set is recorded, not raised
        return values, f"parameters: {type(exc).__name__}: {exc}"
    groups = [(("current", "speed", "position"), None, 0.0)]
    if scene.condition("cylinder") == "detached":
        notes.append("force loop: cylinder detached (no force loop)")
    else:
        try:
            groups.append((("force",), load_system_parameters(p, scene), force_demand_peak(scene)))
        except Exception as exc:  # noqa: BLE001
            notes.append(f"force loop: {type(exc).__name__}: {exc}")
    for loops, load_system, force in groups:
        try:
            margins = loop_margins(p, load_system, force, loops=loops)
        except Exception as exc:  # noqa: BLE001 - recorded per loop group
            notes.append(f"{'/'.join(loops)} loop: {type(exc).__name__}: {exc}")
            continue
        for name, (loop, metric) in MARGIN_VARIABLES.items():
            if loop in margins:
                values[name] = float(getattr(margins[loop], metric))
    return values, "; ".join(notes)


#: Runs per margin task when the margins are computed on a cluster (a few ms each: tens of ms per task).
MARGIN_CHUNK = 50


def margin_chunk(requests: list[RunRequest]) -> list[tuple[dict[str, float], str]]:
    """:func:`run_margins` of several runs, in order (one task on a cluster)."""
    return [run_margins(request) for request in requests]


def margin_variables(spec, request_of, map_chunks=None) -> dict:
    """``results.nc`` variables ``(dataset, run)`` of the loop margins of every run.

    ``request_of(d, i)`` is the run's :class:`campaigns.runner.runs.RunRequest`
    (:func:`campaigns.runner.execution.build_request`). Variables carry CF ``units``, ``long_name`` and
    ``role = "margin"`` (not features: the feature machinery skips them); :data:`MARGIN_NOTE` holds
    why a margin is NaN. ``map_chunks(margin_chunk, chunks)`` returns each chunk's result in order,
    e.g. computed in parallel on the campaign's cluster (a run's margins do not depend on where
    they are computed); default: here, one chunk after the other.
    """
    shape = (len(spec.datasets), spec.runs_per_dataset)
    keys = [(d, i) for d in range(shape[0]) for i in range(shape[1])]
    chunks = [[request_of(d, i) for d, i in keys[k:k + MARGIN_CHUNK]] for k in range(0, len(keys), MARGIN_CHUNK)]
    results = map_chunks(margin_chunk, chunks) if map_chunks else [margin_chunk(chunk) for chunk in chunks]
    arrays = {name: np.full(shape, math.nan) for name in MARGIN_VARIABLES}
    notes = np.full(shape, "", dtype=object)
    for (d, i), (values, note) in zip(keys, (result for chunk in results for result in chunk), strict=True):
        notes[d, i] = note
        for name, value in values.items():
            arrays[name][d, i] = value
    dims = ("dataset", "run")
    out = {}
    for name, (loop, metric) in MARGIN_VARIABLES.items():
        unit, long_name = METRICS[metric]
        values, attrs = arrays[name], {}
        if unit == "dB":  # an amplitude ratio in dB; stored as the ratio, which every unit library reads alike
            values, unit = 10.0 ** (values / 20.0), "1"
            attrs["comment"] = "amplitude ratio (gain margin in dB = 20 log10 of it); inf: no phase crossover"
        out[name] = (dims, values, {"units": unit, "long_name": f"{loop} loop {long_name} (twin.control.margins)",
                                    "role": "margin", "loop": loop, "metric": metric, **attrs})
    out[MARGIN_NOTE] = (dims, notes, {"long_name": "why loop margins are NaN (empty: every present loop computed)"})
    return out


#: Relative round-off a sampled range may have beyond a bound it was written at (unit conversion of the bound).
BOUND_ROUND_OFF = 1e-9


def support_checks(spec, parameter_set: str) -> tuple[list[str], list[str]]:
    """Every sampled range, and every data set's fixed parameter, against what its target allows, before anything
    runs: ``(problems, warnings)``.

    A problem: a range (uniform, truncated Gaussian: its bounds; a constant: its value; a Gaussian or lognormal:
    its centre) outside the bounds of the parameter file or of the scene condition, which every run would fail on.
    A warning: a Gaussian whose tail crosses a bound (the share of runs that would fail is given) or a centre more
    than ``twin.parameters.PLAUSIBLE_FACTOR`` times away from the nominal (a unit or exponent slip, usually).
    The bounds are the bench's: its parameter set ``parameter_set`` and ``twin.scenes.CONDITIONS``.
    """
    parameters = _parameters(parameter_set)
    problems, warnings = [], []
    for k, row in enumerate(spec.uncertainties):
        d = row.distribution_resolved
        conditions, _ = split_targets({d.target: None})
        name = next(iter(conditions), None)
        exact = ((lambda v, c=CONDITIONS[name]: c.check(v)) if name in CONDITIONS
                 else (lambda v, p=parameters[d.target]: p.check(v) is None) if name is None else None)
        # a range given as the bound itself (a sensor's Table 9.5 range) may land a last bit beyond it in SI units
        check = exact and (lambda v, exact=exact: any(exact(v * (1.0 + e))
                                                      for e in (0.0, -BOUND_ROUND_OFF, BOUND_ROUND_OFF)))
        if check is None or not CONDITIONS.get(name, CONDITIONS["backlash"]).numeric:
            continue
        allowed = (f"{CONDITIONS[name].allowed}" if name is not None
                   else f"{parameters[d.target].allowed()} {d.unit}")
        if d.kind in ("uniform", "truncated_gaussian"):
            edges = [("low", d.low), ("high", d.high)]
        elif d.kind == "constant":
            edges = [("value", d.value)]
        else:
            edges = [("centre", d.mean)]
        for what, value in edges:
            if not check(value):
                problems.append(f"uncertainties[{k}]: {d.target}: the range's {what} {value:g} {d.unit} is outside "
                                f"the allowed range {allowed}; every run drawing it would fail")
        if d.kind == "gaussian" and check(d.mean) and d.sigma > 0:
            for side in (-1.0, 1.0):
                edge = d.mean + side * 3.0 * d.sigma
                if not check(edge):
                    warnings.append(f"uncertainties[{k}]: {d.target}: the Gaussian (mean {d.mean:g}, sigma {d.sigma:g} "
                                    f"{d.unit}) reaches beyond the allowed range {allowed} within 3 sigma: its draws "
                                    "beyond it fail (use truncated_gaussian to keep them inside)")
                    break
        centre = d.value if d.kind == "constant" else d.mean if math.isfinite(d.mean) else 0.5 * (d.low + d.high)
        if name is None and (warning := parameters[d.target].implausible(centre)) is not None:
            warnings.append(f"uncertainties[{k}]: {warning}")
    for k, dataset in enumerate(spec.datasets):
        for name, value in dataset.parameters.items():
            if (problem := parameters[name].check(value)) is not None:
                problems.append(f"datasets[{k}].parameters: {problem}; every run of the data set would fail")
            elif (warning := parameters[name].implausible(value)) is not None:
                warnings.append(f"datasets[{k}].parameters: {warning}")
    return problems, warnings


class BenchCatalog:
    """Catalog of the bench twin for one parameter set and base scene.

    Parameters
    ----------
    parameters : str
        Parameter-set name or path (``twin.load_parameters``).
    scene : str
        Base scene name or path (``twin.load_scene``); its conditions are the
        nominal values of ``scene.*`` targets.

    Raises
    ------
    twin.errors.InputError
        If the twin, the parameter set or the scene cannot be loaded.
    """

    feature_units = BENCH_FEATURES

    def __init__(self, parameters: str = "bench", scene: str = "nominal"):
        try:
            params = twin.load_parameters(parameters)
            base_scene = twin.load_scene(scene)
            self.scene_names = list(twin.list_scenes())
            self.condition_names = list(CONDITIONS)
        except InputError:
            raise
        except Exception as exc:  # twin missing or broken: report it as a spec problem
            raise InputError("bench twin", [f"cannot load parameters {parameters!r} / scene {scene!r}: "
                                            f"{type(exc).__name__}: {exc}"]) from exc
        self._parameters = {n: (params[n].value, params[n].unit) for n in params.names}
        self.condition_units = condition_units()
        self._conditions = {k: (v, self.condition_units[k]) for k, v in scene_conditions(base_scene).items()}

    @property
    def parameter_names(self) -> list[str]:
        return list(self._parameters)

    def nominal(self, target: str) -> tuple[float, str]:
        return lookup_nominal(target, self._parameters, self._conditions)

    def support_checks(self, spec) -> tuple[list[str], list[str]]:
        """The spec's sampled ranges and fixed parameters against the bench's bounds (:func:`support_checks`), and
        its solver's engine against this machine (a CUDA engine without a GPU is refused before any run)."""
        problems, warnings = support_checks(spec, spec.base.parameters)
        try:
            twin.Solver(engine=spec.solver.engine)
        except InputError as exc:
            problems += [f"solver.{p}" for p in exc.problems]
        return problems, warnings


@lru_cache(maxsize=8)
def _scene(name: str):
    return twin.load_scene(name)


def run_scene(request: RunRequest):
    """The scene a run simulates: the data set's scene, its test procedure, then its conditions."""
    return _scene(request.scene).with_procedure(request.procedure).with_conditions(request.conditions)


@lru_cache(maxsize=2)
def _parameters(name: str):
    return twin.load_parameters(name)


def simulate_one(request: RunRequest) -> dict:
    """One run: one ``twin.simulate`` call (see :mod:`campaigns.runner.runs` for the contract).

    The run's noise generator goes to ``twin.simulate``; the compiled loop cannot
    be interrupted from inside, so the per-run timeout is the sandbox's kill
    (:mod:`campaigns.runner.sandbox`); without isolation a run that returns over its
    budget is recorded as ``timeout`` (:func:`campaigns.runner.runs.execute`).
    """
    scene = run_scene(request)
    params = _parameters(request.parameters).with_values(request.parameter_values)
    solver, options = split_solver({k: v for k, v in request.solver.items() if v is not None})
    options.update(throw=False, rng=request.noise_rng(), outputs=list(request.outputs) or None)
    if not request.trace_variables:  # scalars only: no Dataset to build (save="features", same numbers)
        summary = twin.simulate(scene, params, solver=solver, save="features", **options)
        return {"status": summary.status, "failure_reason": summary.failure_reason, "t_reached": summary.t_reached,
                "features": {f: float(summary.features[f]) for f in request.features if f in summary.features},
                "trace": None, "fidelity": summary.fidelity,
                "integrator": solver_label(summary.integrator, summary.dt)}
    ds = twin.simulate(scene, params, solver=solver, **options)
    kept = [v for v in request.trace_variables if v in ds]
    return {
        "status": ds.attrs.get("status", "ok"),
        "failure_reason": ds.attrs.get("failure_reason", ""),
        "t_reached": float(ds.attrs.get("t_reached", math.nan)),
        "features": {f: float(ds[f]) for f in request.features if f in ds},
        "trace": ds[kept].isel(time=slice(None, None, request.trace_decimation)),
        "fidelity": ds.attrs.get("fidelity", ""),
        "integrator": solver_label(ds.attrs.get("integrator", ""), float(ds.attrs.get("dt", math.nan))),
    }


def simulate_group(requests: list[RunRequest]) -> list[dict]:
    """:func:`simulate_one` of several runs of one data set at once: the untraced ones in the twin's lock-step lanes
    (:func:`twin.simulate_batch`, the same numbers as each alone), the traced ones one by one (their Dataset).
    Raises if a request cannot be built (the caller then runs each alone and records its own failure)."""
    results: dict[int, dict] = {}
    untraced = [k for k, r in enumerate(requests) if not r.trace_variables]
    for k, request in enumerate(requests):
        if request.trace_variables:
            results[k] = simulate_one(request)
    if untraced:
        first = requests[untraced[0]]
        solver, options = split_solver({key: value for key, value in first.solver.items() if value is not None}
                                       | {"lanes": len(untraced)})
        options.update(throw=False, outputs=list(first.outputs) or None)
        runs = [(run_scene(requests[k]),
                 _parameters(requests[k].parameters).with_values(requests[k].parameter_values),
                 requests[k].noise_rng()) for k in untraced]
        for k, summary in zip(untraced, twin.simulate_batch(runs, solver=solver, **options), strict=True):
            request = requests[k]
            results[k] = {"status": summary.status, "failure_reason": summary.failure_reason,
                          "t_reached": summary.t_reached,
                          "features": {f: float(summary.features[f]) for f in request.features
                                       if f in summary.features},
                          "trace": None, "fidelity": summary.fidelity,
                          "integrator": solver_label(summary.integrator, summary.dt)}
    return [results[k] for k in range(len(requests))]


def _warm_up(request: RunRequest) -> None:
    """Load (or compile) the compiled loop with a 10 ms run of the request's configuration, before the
    run's clock starts (:func:`campaigns.runner.runs.warm_up`)."""
    # the warm-up lasts 10 ms whatever the run's own duration (a request may carry one in its solver options)
    solver, options = split_solver({k: v for k, v in request.solver.items() if v is not None and k != "duration"})
    twin.simulate(_scene(request.scene).with_procedure(request.procedure), _parameters(request.parameters),
                  solver=solver, throw=False, duration=0.01,
                  outputs=list(request.outputs) or None, **options)


@dataclass(frozen=True)
class BenchModel:
    """The bench twin as the runner's run model (:class:`campaigns.runner.runs.RunModel`): one run, lock-step lane
    groups, the compile warm-up, what a run costs, and the data sets' conditions and loop margins in ``results.nc``.
    """

    #: Runs a group takes at once (the results do not depend on it: :func:`simulate_group`): the twin's default group
    #: (docs/performance.md, "The stages after the runs" and "Lanes per group").
    lanes: int = DEFAULT_LANES
    #: Wall time a worker spends per 10 s data-set run of a campaign [s]: in 16-lane groups, with the per-run work
    #: around them (the budget's estimate; measured on the demo: docs/performance.md, "The figures behind the campaign
    #: code's constants"). One run alone takes several times as long: it is no campaign's cost.
    typical_run_seconds: float = 0.2
    #: The step that time holds for: the twin's default.
    typical_step: float = DEFAULT_DT
    #: Samples of a trace before decimation: 10 s at the 1 ms output spacing, both ends included.
    trace_samples: int = 10_001
    #: numba compiles the twin's loop on first use (its on-disk cache then serves every worker).
    compiles: bool = True

    def __call__(self, request: RunRequest) -> dict:
        return simulate_one(request)

    def run_group(self, requests: list[RunRequest]) -> list[dict]:
        return simulate_group(requests)

    def warm_up(self, request: RunRequest) -> None:
        _warm_up(request)

    def signals(self) -> tuple[str, ...]:
        """Every signal and feature the twin can return (what a replay keeps, :mod:`campaigns.bench.replay`)."""
        return OUTPUT_NAMES

    def results_attributes(self, spec) -> dict[str, str]:
        """Every condition of each data set's effective scene and of the base scene (:func:`dataset_conditions`)."""
        conditions, base = dataset_conditions(spec)
        return {"dataset_conditions": json.dumps(conditions), "base_scene_conditions": json.dumps(base)}

    def margin_variables(self, spec, request_of, map_chunks) -> dict:
        return margin_variables(spec, request_of, map_chunks=map_chunks)


#: The bench twin's run model, the campaigns' default (``results.nc`` records it as
#: ``campaigns.bench.adapter:simulate_run``).
simulate_run = BenchModel()
