"""``simulate``: the single entry point that runs one bench test (and ``simulate_batch``, many, in lock-step lanes).

How a run is integrated is one :class:`twin.solver.Solver` argument; the entries hold what is run (scene,
parameters, duration, fidelity, outputs, curvature, noise) and what is saved (signals or features alone).
"""

from __future__ import annotations

import json
import math
import time
from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from twin.engine.group import group_key
from twin.engine.instrumentation import build_instruments, group_timing
from twin.engine.integrators import INTEGRATORS
from twin.engine.model import CURVATURE_FORMULAS, build_model
from twin.engine.reference import METHODS as REFERENCE_METHODS
from twin.engine.reference import local_error_tolerance, run_reference
from twin.errors import InputError, OptionError, SimulationFailed
from twin.features import FEATURES, N_ACCUMULATORS, finish
from twin.fidelity import Fidelity, resolve_fidelity
from twin.fidelity.rules import peak_demand_speed
from twin.layout import BOUND_REASONS, N_MEMORY, N_SIGNALS, SIGNAL_META, STATUS_OK, STATUS_TEXT, M, S, Signal
from twin.parameters import ParameterSet, load_parameters
from twin.physics.bristle_friction import rk4_step_problems
from twin.scenes import ZERO_PROCEDURES, Scene, load_scene
from twin.solver import DEFAULT_SOLVER, Solver

DEFAULT_OUTPUT_DT = 1.0e-3  # s; the controller's acquisition period
NOMINAL_SLED_SPEED = 0.07  # m/s: Table 9.3's nominal bench speed, the least sliding speed the seal check assumes
DEFAULT_NOISE_SEED = 0      # rng=None: a fixed seed, so a bare call is reproducible
#: What :func:`simulate` returns: the recorded signals with the features (an xarray Dataset), or the status and
#: scalar features alone (a :class:`RunSummary`, no signals recorded: a Monte Carlo campaign's runs).
SAVES = ("signals", "features")
#: A run's time axis: seconds from the start of the test procedure, a plain quantity (no reference date: a CF time
#: unit, "s since <date>", would have every netCDF reader turn the test's 10 s into dates of 1970).
TIME_ATTRS = {"units": "s", "long_name": "time since the start of the test procedure"}


def _steps_per(period: float, dt: float, what: str, problems: list[str]) -> int:
    n = round(period / dt)
    if n < 1 or abs(n * dt - period) > 1e-9 * period:
        problems.append(f"dt: {dt:g} s must divide the {what} ({period:g} s) into a whole number of steps")
        return 1
    return n


def simulate(scene: Scene | str = "nominal", params: ParameterSet | str | None = None, *,
             solver: Solver = DEFAULT_SOLVER, save: str = "signals", output_dt: float = DEFAULT_OUTPUT_DT,
             duration: float | None = None, fidelity: str | Mapping[str, str] = "auto",
             outputs: Sequence[str] | None = None, rng: np.random.Generator | int | None = None,
             curvature: str = "thesis", throw: bool = True) -> xr.Dataset | RunSummary:
    """Run one bench test.

    Parameters
    ----------
    scene : Scene or str
        Test procedure or the name/path of one (see :func:`twin.list_scenes`).
    params : ParameterSet, str or None
        Parameter set or its name/path; ``None`` is the built-in ``"bench"`` set.
    solver : Solver
        How the run is integrated (:class:`twin.Solver`: method, step, tolerance, guard); default ``Solver()``,
        RK4 at its default step.
    save : {"signals", "features"}
        ``"signals"`` (default) returns the xarray Dataset below; ``"features"`` returns a :class:`RunSummary`
        (status, reason, ``t_reached``, fidelity and every scalar feature) without recording the signals: the
        same numbers as the Dataset's, bit for bit.
    output_dt : float
        Spacing of the recorded signals [s]; a multiple of the step (default 1 ms, the acquisition period).
    duration : float, optional
        Override of the scene's duration [s].
    fidelity : "auto", "full" or mapping
        Level of every subsystem (:mod:`twin.fidelity`): ``"auto"`` models no more than
        the scene's demands, duration and ``outputs`` need (rules in
        ``twin/fidelity/rules.toml``); ``"full"`` is the most detailed model; a mapping
        ``{subsystem: level}`` sets some and leaves the others to its ``"default"``
        entry (``"auto"`` unless given). The choice and its reasons are in
        ``attrs["fidelity"]`` and ``attrs["fidelity_reasons"]``.
    outputs : sequence of str, optional
        Signals and features the caller needs (:data:`twin.layout.OUTPUT_NAMES`);
        ``None`` takes the scene's ``outputs`` (all, if it names none). Signals a
        reduced level does not compute are left out of the result.
    rng : numpy.random.Generator, int or None
        Source of the electrical noise (Table 9.5); an int seeds a new Generator;
        ``None`` uses seed 0. Same generator state, same noise.
    curvature : {"thesis", "iso"}
        Groove curvature formulas (Eqs. 3.20/3.27 or 3.21/3.28).
    throw : bool
        If True, a diverged run raises :class:`twin.SimulationFailed`; if False it
        is returned as data: ``attrs["status"] != "ok"`` with ``failure_reason``
        and ``t_reached``, and the signals up to that time.

    Returns
    -------
    xarray.Dataset or RunSummary
        With ``save="signals"``: true and measured signals on ``time`` [s] with ``units`` attributes, the
        scalar features of :data:`twin.features.FEATURES` (``backlash_feature``,
        Eq. 9.12, and ``backlash_hysteresis`` on the measured encoder signals; ``*_true``
        on true signals), and run metadata in ``attrs``, among them the scene's
        ``zero_procedure`` and ``cylinder`` and every condition in ``scene_conditions`` (JSON).
        With ``save="features"``: the :class:`RunSummary` of those attributes and features.

    Raises
    ------
    OptionError, SceneError, ParameterError
        On invalid input, before anything runs.
    """
    if save not in SAVES:
        raise OptionError([f"save: {save!r} is not one of {', '.join(SAVES)}"])
    run = _validated(scene, params, solver, output_dt, duration, fidelity, outputs, rng, curvature)
    done = _thrown(_solved([_prepared(run, rng, record=save == "signals")])[0], throw)
    return _package(done) if save == "signals" else _summary(done)


def simulate_batch(runs: Sequence[tuple[Scene | str, ParameterSet | str | None, np.random.Generator | int | None]],
                   *, solver: Solver = DEFAULT_SOLVER, output_dt: float = DEFAULT_OUTPUT_DT,
                   duration: float | None = None, fidelity: str | Mapping[str, str] = "auto",
                   outputs: Sequence[str] | None = None, curvature: str = "thesis",
                   throw: bool = True) -> list[RunSummary]:
    """:func:`simulate` of many runs ``(scene, params, rng)`` with the same options and ``save="features"``,
    advanced in lock-step lanes: runs whose model configuration agrees (fidelity levels, integrated states, demand
    profiles) share groups of up to ``solver.lanes`` lanes. Each summary equals that of the run alone, bit for bit,
    whatever the grouping (tests/engine/test_lanes.py). Returned in the order of ``runs``.

    Raises
    ------
    OptionError, SceneError, ParameterError
        On invalid input of any run, before anything runs.
    """
    prepared = [_prepared(_validated(scene, params, solver, output_dt, duration, fidelity, outputs, rng, curvature),
                          rng, record=False)
                for scene, params, rng in runs]
    return [_summary(_thrown(done, throw)) for done in _solved(prepared, solver.lanes)]


@dataclass(frozen=True)
class RunSummary:
    """What ``simulate(..., save="features")`` returns: the ``attrs`` and scalar features of its Dataset."""

    status: str             # attrs["status"]
    failure_reason: str     # attrs["failure_reason"]
    t_reached: float        # attrs["t_reached"] [s]
    fidelity: str           # attrs["fidelity"]
    features: dict[str, float]  # every feature of twin.features.FEATURES (NaN unless the run is ok)
    integrator: str = ""    # attrs["integrator"]: the method that solved the run
    dt: float = math.nan    # attrs["dt"]: its step [s]


@dataclass(frozen=True)
class _Run:
    """A validated request: the loaded scene and parameters, the resolved fidelity and the step counts."""

    scene: Scene
    params: ParameterSet
    fidelity: Fidelity
    solver: Solver
    dt: float  # the step the solver takes on this run [s] (Solver.step)
    curvature: str
    speed_sample_time: float
    speed_every: int
    position_every: int
    output_every: int

    @property
    def n_steps(self) -> int:
        return int(round(self.scene.duration / self.dt))


@dataclass(frozen=True)
class _Prepared:
    """A run ready for the loop: its model, instruments and options."""

    run: _Run
    model: object
    instruments: object
    rng: object
    tolerance: np.ndarray
    record: bool


@dataclass(frozen=True)
class _Simulated:
    """A finished run before packaging: the request, the model and the loop's buffers."""

    run: _Run
    model: object
    x: np.ndarray
    output: np.ndarray
    memory: np.ndarray
    status: int
    bound: int
    reason: str
    t_reached: float
    solver_stats: dict
    wall_time: float
    rng: object


def _prepared(run: _Run, rng, record: bool) -> _Prepared:
    """Build the run's model and instruments (the noise drawn from its generator)."""
    generator = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(
        DEFAULT_NOISE_SEED if rng is None else rng)
    model = build_model(run.scene, run.params, run.fidelity, curvature=run.curvature)
    instruments = build_instruments(run.params.values(), run.scene.condition("room_temperature"), run.fidelity.levels,
                                    generator, run.n_steps // run.position_every + 1, run.dt)
    tolerance = local_error_tolerance() * (1.0 if run.solver.local_error_guard else np.inf)
    return _Prepared(run, model, instruments, rng, tolerance, record)


def _solved(prepared: list[_Prepared], lanes: int = 1) -> list[_Simulated]:
    """Solve every prepared run: the reference path one by one, the compiled loop in groups of up to ``lanes``
    runs that share a configuration. In the order given."""
    done: list[_Simulated | None] = [None] * len(prepared)
    groups: dict[tuple, list[int]] = defaultdict(list)
    for k, p in enumerate(prepared):
        if p.run.solver.reference:
            done[k] = _reference(p)
        else:
            run = p.run
            groups[(group_key(p.model), group_timing(p.instruments), run.solver.integrator, run.dt, run.n_steps,
                    run.speed_every, run.position_every, run.output_every if p.record else 0,
                    p.tolerance.tobytes())].append(k)
    for members in groups.values():
        for first in range(0, len(members), lanes):
            chunk = members[first:first + lanes]
            for k, simulated in zip(chunk, _compiled([prepared[k] for k in chunk]), strict=True):
                done[k] = simulated
    return done


def _compiled(prepared: list[_Prepared]) -> list[_Simulated]:
    """One lane group on the compiled loop."""
    run = prepared[0].run
    start = time.perf_counter()
    solve = run.solver.group_solver()
    solved = solve([p.model for p in prepared], [p.instruments for p in prepared], n_steps=run.n_steps,
                   dt=run.dt, speed_every=run.speed_every, position_every=run.position_every,
                   output_every=run.output_every if prepared[0].record else 0,
                   jacobian_every=run.position_every, method=INTEGRATORS[run.solver.integrator],
                   tolerance=prepared[0].tolerance)
    wall_time = (time.perf_counter() - start) / len(prepared)  # a lane's share of the group's wall time
    out = []
    for lane, p in enumerate(prepared):
        rows = int(solved.rows_written[lane])
        bound = int(solved.bound[lane])
        out.append(_Simulated(p.run, p.model, solved.state[:, lane].copy(), solved.output[:rows, :, lane],
                              solved.memory[:, lane].copy(), int(solved.status[lane]), bound, BOUND_REASONS[bound],
                              int(solved.steps_done[lane]) * p.run.dt, {}, wall_time, p.rng))
    return out


def _reference(p: _Prepared) -> _Simulated:
    """One run on the adaptive reference path (scipy's solve_ivp)."""
    run, model = p.run, p.model
    n_speed = int(round(run.scene.duration / run.speed_sample_time))
    output = np.full((n_speed // run.output_every + 1, N_SIGNALS), np.nan)
    memory = np.zeros(N_MEMORY)
    x = model.initial_state.copy()
    start = time.perf_counter()
    status, bound, t_reached, rows, reason, solver_stats = run_reference(
        model, p.instruments, n_speed, run.speed_sample_time, run.position_every, run.output_every, output, memory,
        REFERENCE_METHODS[run.solver.integrator], run.solver.rtol, x)
    return _Simulated(run, model, x, output[:rows], memory, status, bound, reason or BOUND_REASONS[bound], t_reached,
                      solver_stats, time.perf_counter() - start, p.rng)


def _thrown(done: _Simulated, throw: bool) -> _Simulated:
    if done.status != STATUS_OK and throw:
        raise SimulationFailed(STATUS_TEXT[done.status], done.reason, done.t_reached)
    return done


def _validated(scene, params, solver, output_dt, duration, fidelity, outputs, rng, curvature) -> _Run:
    """Load the inputs, check every option against them and resolve the fidelity; every problem in one
    :class:`OptionError`. The solver has checked its own fields when it was made (:class:`twin.Solver`)."""
    if not isinstance(solver, Solver):
        raise OptionError([f"solver: expected a twin.Solver, got {type(solver).__name__}"])
    scene = load_scene(scene)
    if not isinstance(params, ParameterSet):
        params = load_parameters("bench" if params is None else params)
    if duration is not None:
        scene = scene.with_duration(duration)
    problems: list[str] = []
    speed_ts = params.value("drive.speed_loop_sample_time")
    if curvature not in CURVATURE_FORMULAS:
        problems.append(f"curvature: {curvature!r} is not one of {', '.join(CURVATURE_FORMULAS)}")
    resolved = None
    if curvature in CURVATURE_FORMULAS:
        try:
            resolved = resolve_fidelity(scene, params, fidelity, outputs, curvature)
        except InputError as exc:
            problems += exc.problems
    if rng is not None and not isinstance(rng, (np.random.Generator, int)):
        problems.append(f"rng: expected a numpy Generator, an int seed or None, got {type(rng).__name__}")
    if resolved is not None:
        problems += solver.conflicts(resolved)
    dt = solver.step(resolved, speed_ts)
    if resolved is not None and solver.integrator == "rk4" and resolved.level("pneumatics") == "full":
        problems += _seal_step_problems(scene, params, resolved.level("seal_friction"), dt)
    speed_every = _steps_per(speed_ts, dt, "speed-loop period", problems)
    position_every = _steps_per(params.value("controller.position_loop_sample_time"), dt, "position-loop period",
                                problems)
    output_every = _steps_per(output_dt, dt, "output spacing output_dt", problems) if output_dt > 0 else 1
    if problems:
        raise OptionError(list(dict.fromkeys(problems)))
    return _Run(scene, params, resolved, solver, dt, curvature, speed_ts, speed_every, position_every, output_every)


def _seal_step_problems(scene: Scene, params: ParameterSet, level: str, dt: float) -> list[str]:
    """The seal friction's eigenvalues against RK4's reach at ``dt`` (:func:`twin.physics.bristle_friction.
    rk4_step_problems`): a presliding stiffness, a regularisation speed or a piston mass that would make the run
    diverge is refused before it starts, naming the field. The sliding relaxation grows with the speed: the largest
    the position demand asks for, at least Table 9.3's nominal 0.07 m/s (a scene that holds the sled still can still
    be pushed by its force loop)."""
    seal = {key: value for key, value in params.values().items() if key.startswith("pneumatics.")}
    return rk4_step_problems(level, seal, dt, max(peak_demand_speed(scene), NOMINAL_SLED_SPEED))


def _features(done: _Simulated) -> dict[str, float]:
    """Every feature of :data:`twin.features.FEATURES` from the loop's accumulators (NaN unless the run is ok)."""
    memory = done.memory
    ok = done.status == STATUS_OK and memory[M.SAMPLES] > 0
    values = {}
    for suffix, block in (("", M.FEATURES_MEASURED), ("_true", M.FEATURES_TRUE)):
        for base, value in finish(memory[block:block + N_ACCUMULATORS], memory[M.SAMPLES]).items():
            values[base + suffix] = value if ok else np.nan
    return values


def _summary(done: _Simulated) -> RunSummary:
    return RunSummary(STATUS_TEXT[done.status], done.reason, done.t_reached, done.run.fidelity.summary(),
                      _features(done), done.run.solver.integrator, done.run.dt)


def _package(done: _Simulated) -> xr.Dataset:
    """The run as an xarray Dataset: signals on the output grid, the features (:mod:`twin.features`), the final
    state and the attributes that say how it was computed."""
    run, model, x, output, memory = done.run, done.model, done.x, done.output, done.memory
    status, reason, t_reached, solver_stats, wall_time, rng = (done.status, done.reason, done.t_reached,
                                                               done.solver_stats, done.wall_time, done.rng)
    scene, params, resolved, dt = run.scene, run.params, run.fidelity, run.dt
    time_axis = np.arange(output.shape[0]) * run.output_every * dt
    removed = set(resolved.removed_signals)
    data_vars = {
        signal.name.lower(): ("time", output[:, signal],
                              {"units": SIGNAL_META[signal][0], "long_name": SIGNAL_META[signal][1]})
        for signal in Signal
        if signal.name.lower() not in removed
    }
    for name, value in _features(done).items():
        feature = FEATURES[name]
        data_vars[name] = ((), value, {"units": feature.unit, "long_name": feature.long_name,
                                       "description": feature.description})
    data_vars["final_state"] = ("state", x[model.active], {
        "long_name": "integrated states at t_reached (SI units, layout twin.layout.S)"})
    return xr.Dataset(
        data_vars,
        coords={"time": ("time", time_axis, TIME_ATTRS),
                "state": ("state", [S(j).name.lower() for j in model.active])},
        attrs={
            "status": STATUS_TEXT[status],
            "failure_reason": reason,
            "t_reached": t_reached,
            "scene": scene.name,
            "zero_procedure": scene.condition("zero_procedure"),
            "zero_procedure_description": ZERO_PROCEDURES[scene.condition("zero_procedure")],
            "cylinder": scene.condition("cylinder"),
            "scene_conditions": json.dumps(dict(scene.conditions)),
            "parameter_set": params.name,
            "screw_lead": params.value("ball_screw.lead"),
            "integrator": run.solver.integrator,
            "dt": dt,
            **({"rtol": run.solver.rtol, **{f"solver_{k}": v for k, v in solver_stats.items()}}
               if run.solver.reference else {}),
            "curvature": run.curvature,
            "fidelity": resolved.summary(),
            "fidelity_reasons": "\n".join(f"{k}: {v}" for k, v in resolved.reasons.items()),
            "integrated_states": int(model.active.size),
            "noise_seed": ("caller generator" if isinstance(rng, np.random.Generator)
                           else str(DEFAULT_NOISE_SEED if rng is None else rng)),
            "wall_time": wall_time,
            "max_local_error": float(memory[M.LOCAL_ERROR]),
        },
    )
