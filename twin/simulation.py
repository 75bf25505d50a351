"""``simulate``: the single entry point that runs one bench test and returns an xarray Dataset."""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from twin.engine.instrumentation import build_instruments, instrument_levels
from twin.engine.integrators import INTEGRATORS
from twin.engine.loop import run_loop
from twin.engine.model import CURVATURE_FORMULAS, build_model
from twin.engine.reference import METHODS as REFERENCE_METHODS
from twin.engine.reference import local_error_tolerance, run_reference
from twin.engine.solver_choice import (
    IMPLICIT_METHOD,
    RELEASE_BUDGET,
    choice_statement,
    held_interference,
    rk4_limit_at_start,
)
from twin.errors import InputError, OptionError, SimulationFailed
from twin.features import FEATURES, N_ACCUMULATORS, finish
from twin.fidelity import Fidelity, resolve_fidelity
from twin.layout import (
    BOUND_REASONS,
    N_MEMORY,
    N_SIGNALS,
    SIGNAL_META,
    STATUS_OK,
    STATUS_TEXT,
    M,
    S,
    Signal,
)
from twin.parameters import ParameterSet, load_parameters
from twin.scenes import ZERO_PROCEDURES, Scene, load_scene

DEFAULT_INTEGRATOR = "rk4"  # "auto" (twin.engine.solver_choice) is opt-in: docs/accuracy.md says why
DEFAULT_DT = 6.25e-5  # s; chosen by the speed-versus-accuracy study (docs/accuracy.md)
AUTO = "auto"
DEFAULT_OUTPUT_DT = 1.0e-3  # s; the controller's acquisition period
DEFAULT_NOISE_SEED = 0      # rng=None: a fixed seed, so a bare call is reproducible


def _steps_per(period: float, dt: float, what: str, problems: list[str]) -> int:
    n = round(period / dt)
    if n < 1 or abs(n * dt - period) > 1e-9 * period:
        problems.append(f"dt: {dt:g} s must divide the {what} ({period:g} s) into a whole number of steps")
        return 1
    return n


def simulate(scene: Scene | str = "nominal", params: ParameterSet | str | None = None, *,
             integrator: str = DEFAULT_INTEGRATOR, dt: float | None = None, output_dt: float = DEFAULT_OUTPUT_DT,
             duration: float | None = None, fidelity: str | Mapping[str, str] = "auto",
             outputs: Sequence[str] | None = None, rng: np.random.Generator | int | None = None,
             curvature: str = "thesis", rtol: float = 1e-10, local_error_guard: bool = True,
             throw: bool = True) -> xr.Dataset:
    """Run one bench test.

    Parameters
    ----------
    scene : Scene or str
        Test procedure or the name/path of one (see :func:`twin.list_scenes`).
    params : ParameterSet, str or None
        Parameter set or its name/path; ``None`` is the built-in ``"bench"`` set.
    integrator : {"auto", "rk4", "semi_implicit_euler", "rosenbrock_w2", "imex_euler", "scipy_radau",
                  "scipy_lsoda", "scipy_bdf", "scipy_rk45"}
        A fixed-step method of the compiled loop (default ``rk4`` at 62.5 us), a ``scipy_*`` adaptive method
        of the reference path (:mod:`twin.engine.reference`), which ignores ``dt``, or ``"auto"``
        (:mod:`twin.engine.solver_choice`, opt-in): ``imex_euler`` at the 125 us drive period while both nuts
        are held on a flank, else the whole run again with ``rk4``, at 125 us if that run stays stable and its
        local-error estimate never exceeds the tolerance, else at 62.5 us; the method used and why are in
        ``attrs["integrator"]``, ``attrs["dt"]`` and ``attrs["integrator_choice"]``. About 3x faster where the
        implicit step is kept, but not accurate everywhere the premise holds (docs/accuracy.md).
    dt : float, optional
        Integration step [s]; must divide the speed- and position-loop periods. Default 62.5 us;
        ``"auto"`` chooses its own.
    output_dt : float
        Spacing of the recorded signals [s]; a multiple of ``dt``.
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
    rtol : float
        Relative tolerance of the ``scipy_*`` reference path.
    local_error_guard : bool
        The finite-but-wrong guard (:func:`twin.engine.loop.local_error`); switch it off
        only to demonstrate what it catches (``"auto"`` keeps it on for its RK4 attempt at the
        drive period, which it judges by it).
    throw : bool
        If True, a diverged run raises :class:`twin.SimulationFailed`; if False it
        is returned as data: ``attrs["status"] != "ok"`` with ``failure_reason``
        and ``t_reached``, and the signals up to that time.

    Returns
    -------
    xarray.Dataset
        True and measured signals on ``time`` [s] with ``units`` attributes, the
        scalar features of :data:`twin.features.FEATURES` (``backlash_feature``,
        Eq. 9.12, and ``backlash_hysteresis`` on the measured encoder signals; ``*_true``
        on true signals), and run metadata in ``attrs``, among them the scene's
        ``zero_procedure`` and ``cylinder`` and every condition in ``scene_conditions`` (JSON).

    Raises
    ------
    OptionError, SceneError, ParameterError
        On invalid input, before anything runs.
    """
    return _package(_simulated(scene, params, integrator, dt, output_dt, duration, fidelity, outputs, rng, curvature,
                               rtol, local_error_guard, throw))


def simulate_features(scene: Scene | str = "nominal", params: ParameterSet | str | None = None, *,
                      integrator: str = DEFAULT_INTEGRATOR, dt: float | None = None,
                      output_dt: float = DEFAULT_OUTPUT_DT, duration: float | None = None,
                      fidelity: str | Mapping[str, str] = "auto", outputs: Sequence[str] | None = None,
                      rng: np.random.Generator | int | None = None, curvature: str = "thesis", rtol: float = 1e-10,
                      local_error_guard: bool = True, throw: bool = True) -> RunSummary:
    """:func:`simulate` without the Dataset: the run's scalar features and status, for callers that
    need nothing else (a Monte Carlo campaign's runs). Same options, same numbers as ``simulate``."""
    return _summary(_simulated(scene, params, integrator, dt, output_dt, duration, fidelity, outputs, rng, curvature,
                               rtol, local_error_guard, throw))


@dataclass(frozen=True)
class RunSummary:
    """What :func:`simulate_features` returns: the ``attrs`` and scalar features of :func:`simulate`'s Dataset."""

    status: str             # attrs["status"]
    failure_reason: str     # attrs["failure_reason"]
    t_reached: float        # attrs["t_reached"] [s]
    fidelity: str           # attrs["fidelity"]
    features: dict[str, float]  # every feature of twin.features.FEATURES (NaN unless the run is ok)
    integrator: str = ""    # attrs["integrator"]: the method that solved the run
    dt: float = math.nan    # attrs["dt"]: its step [s]


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
    choice: str  # the automatic integrator's statement (twin.engine.solver_choice), "" for a named method


def _simulated(scene, params, integrator, dt, output_dt, duration, fidelity, outputs, rng, curvature, rtol,
               local_error_guard, throw) -> _Simulated:
    """Validate, build, solve (the steps :func:`simulate` and :func:`simulate_features` share)."""
    run = _validated(scene, params, integrator, dt, output_dt, duration, fidelity, outputs, rng, curvature, rtol)
    model = build_model(run.scene, run.params, run.fidelity, curvature=run.curvature)
    attempts = [run]  # a named method: one; the automatic integrator: its branches in order (solver_choice)
    while attempts[-1].fallback is not None:
        attempts.append(attempts[-1].fallback)
    # every attempt of the automatic integrator draws the same noise as its first
    pristine = copy.deepcopy(rng) if len(attempts) > 1 and isinstance(rng, np.random.Generator) else None
    stopped, wall_time = [], 0.0
    for k, attempt in enumerate(attempts):
        first, last = k == 0, k == len(attempts) - 1
        explicit_drive_period = not (first or last)  # solver_choice: judged by its stability and local error
        if explicit_drive_period and (limit := rk4_limit_at_start(model)) < attempt.dt:
            stopped.append((attempt.integrator, attempt.dt, None, 0,
                            f"RK4's stability limit at the initial state is {limit * 1e6:.1f} us"))
            continue
        done = _attempt(attempt, model, rng if pristine is None or first else copy.deepcopy(pristine),
                        local_error_guard or explicit_drive_period,
                        held_interference(model) if first and not last else 0.0)
        wall_time += done.wall_time
        if explicit_drive_period and done.status == STATUS_OK and done.memory[M.LOCAL_ERROR] > 1.0:
            # kept only if no local-error check ever exceeded its tolerance (the guard waits for three in a row)
            stopped.append((attempt.integrator, attempt.dt, done.t_reached, 0,
                            f"its local-error estimate reached {done.memory[M.LOCAL_ERROR]:.2f} times the tolerance"))
            continue
        if done.status == STATUS_OK or last:
            break
        # the premise broke, or the branch failed: a failure of the branch, not of the run
        stopped.append((attempt.integrator, attempt.dt, done.t_reached, done.bound, done.reason))
    if len(attempts) > 1:
        done = dataclasses.replace(done, wall_time=wall_time,
                                   choice=choice_statement(done.run.integrator, done.run.dt, stopped))
    if done.status != STATUS_OK and throw:
        raise SimulationFailed(STATUS_TEXT[done.status], done.reason, done.t_reached)
    return done


def _attempt(run: _Run, model, rng, local_error_guard: bool, held: float) -> _Simulated:
    """Solve ``run`` once on ``model``; with ``held`` > 0 [m] the loop stops once the nuts have spent more than the
    release budget below that interference (:mod:`twin.engine.solver_choice`)."""
    generator = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(
        DEFAULT_NOISE_SEED if rng is None else rng)
    n_steps = int(round(run.scene.duration / run.dt))
    instruments = build_instruments(run.params.values(), run.scene.condition("room_temperature"),
                                    instrument_levels(run.fidelity), generator, n_steps // run.position_every + 1,
                                    run.dt,
                                    torque_meter_refresh=run.fidelity.level("torque_meter_refresh") == "modelled")
    output = np.full((n_steps // run.output_every + 1, N_SIGNALS), np.nan)
    memory = np.zeros(N_MEMORY)
    x = model.initial_state.copy()
    start = time.perf_counter()
    status, bound, t_reached, rows, reason, solver_stats = _solve(run, model, instruments, n_steps, x, output, memory,
                                                                  local_error_guard, held)
    return _Simulated(run, model, x, output[:rows], memory, status, bound, reason, t_reached, solver_stats,
                      time.perf_counter() - start, rng, "")


@dataclass(frozen=True)
class _Run:
    """A validated request: the loaded scene and parameters, the resolved fidelity and the step counts."""

    scene: Scene
    params: ParameterSet
    fidelity: Fidelity
    integrator: str
    reference: bool
    dt: float
    rtol: float
    curvature: str
    speed_sample_time: float
    speed_every: int
    position_every: int
    output_every: int
    fallback: _Run | None = None  # the automatic integrator's explicit branch; None for a named method


def _validated(scene, params, integrator, dt, output_dt, duration, fidelity, outputs, rng, curvature, rtol) -> _Run:
    """Load the inputs, check every option and resolve the fidelity; every problem in one :class:`OptionError`."""
    scene = load_scene(scene)
    if not isinstance(params, ParameterSet):
        params = load_parameters("bench" if params is None else params)
    if duration is not None:
        scene = scene.with_duration(duration)
    problems: list[str] = []
    reference = integrator in REFERENCE_METHODS
    auto = integrator == AUTO
    if integrator not in INTEGRATORS and not (reference or auto):
        problems.append(f"integrator: {integrator!r} is not one of "
                        f"{', '.join([AUTO, *INTEGRATORS, *REFERENCE_METHODS])}")
    if auto and dt is not None:
        problems.append(f"dt: {dt!r} with integrator 'auto', which chooses its own steps ({IMPLICIT_METHOD} at the "
                        f"drive period, {DEFAULT_INTEGRATOR} at the drive period or at {DEFAULT_DT * 1e6:g} us); leave "
                        "dt unset or name a method")
    if auto and output_dt == 0:
        problems.append("output_dt: 0 (every step) with integrator 'auto', whose step depends on the run; give a "
                        "spacing, e.g. 1e-3 s")
    speed_ts = params.value("drive.speed_loop_sample_time")
    method = IMPLICIT_METHOD if auto else integrator
    if dt is None or auto:
        dt = speed_ts if auto else DEFAULT_DT
    if not (isinstance(rtol, float) and 1e-14 <= rtol < 1e-2):
        problems.append(f"rtol: {rtol!r} must be a float in [1e-14, 1e-2)")
    if curvature not in CURVATURE_FORMULAS:
        problems.append(f"curvature: {curvature!r} is not one of {', '.join(CURVATURE_FORMULAS)}")
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and 0 < dt <= 1e-3):
        problems.append(f"dt: {dt!r} must be a step in (0, 1e-3] s")
        dt = 1e-3
    resolved = None
    if curvature in CURVATURE_FORMULAS:
        try:
            resolved = resolve_fidelity(scene, params, fidelity, outputs, curvature)
        except InputError as exc:
            problems += exc.problems
    if rng is not None and not isinstance(rng, (np.random.Generator, int)):
        problems.append(f"rng: expected a numpy Generator, an int seed or None, got {type(rng).__name__}")
    if reference:
        dt = speed_ts  # the reference path restarts at each drive sample; dt is its sample grid

    def stepped(name: str, step: float, fallback: _Run | None = None) -> _Run:
        speed_every = _steps_per(speed_ts, step, "speed-loop period", problems)
        position_every = _steps_per(params.value("controller.position_loop_sample_time"), step,
                                    "position-loop period", problems)
        output_every = _steps_per(output_dt, step, "output spacing output_dt", problems) if output_dt > 0 else 1
        return _Run(scene, params, resolved, name, reference, step, rtol, curvature, speed_ts, speed_every,
                    position_every, output_every, fallback)

    explicit = stepped(DEFAULT_INTEGRATOR, DEFAULT_DT) if auto else None
    if auto and speed_ts > DEFAULT_DT:  # the explicit branch tries the drive period first (solver_choice)
        explicit = stepped(DEFAULT_INTEGRATOR, speed_ts, explicit)
    run = stepped(method, dt, explicit)
    if problems:
        raise OptionError(list(dict.fromkeys(problems)))  # the two branches of 'auto' may repeat a problem
    return run


def _solve(run: _Run, model, instruments, n_steps: int, x: np.ndarray, output: np.ndarray, memory: np.ndarray,
           local_error_guard: bool, held: float) -> tuple[int, int, float, int, str, dict]:
    """Integrate on the compiled loop, or on the adaptive reference path; ``x``, ``output`` and ``memory`` are
    filled in place. Returns ``(status, bound code, t_reached, rows of output written, failure reason, solver
    statistics)``."""
    if run.reference:
        status, bound, t_reached, rows, reason, solver_stats = run_reference(
            model, instruments, n_steps, run.speed_sample_time, run.position_every, run.output_every, output, memory,
            REFERENCE_METHODS[run.integrator], run.rtol, x)
        return status, bound, t_reached, rows, reason or BOUND_REASONS[bound], solver_stats
    status, bound, steps_done, rows = run_loop(
        x, model.constants, model.position_table, model.force_table, model.stiffness_poly, model.active,
        model.pairs, n_steps, run.dt, run.speed_every, run.position_every, run.output_every, run.position_every,
        INTEGRATORS[run.integrator], instruments.parameters, instruments.levels, instruments.lookback,
        instruments.noise, memory, output, local_error_tolerance() * (1.0 if local_error_guard else np.inf), held,
        round(RELEASE_BUDGET / run.dt))
    return status, bound, steps_done * run.dt, rows, BOUND_REASONS[bound], {}


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
                      _features(done), done.run.integrator, done.run.dt)


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
        coords={"time": ("time", time_axis, {"units": "s", "long_name": "time"}),
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
            "integrator": run.integrator,
            "dt": dt,
            **({"integrator_choice": done.choice} if done.choice else {}),
            **({"rtol": run.rtol, **{f"solver_{k}": v for k, v in solver_stats.items()}} if run.reference else {}),
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
