"""One run: the request a run model receives, the run model's contract and the outcome recorded for it.

A run model (:class:`RunModel`) is called as ``run_model(request: RunRequest) -> dict`` with keys

``status``
    ``"ok"``, ``"diverged"``, ``"failed"`` or ``"timeout"``;
``failure_reason``
    empty for ``"ok"``;
``t_reached``
    simulated time reached [s];
``features``
    ``{name: float}`` for every feature of the spec;
``trace`` (optional)
    an :class:`xarray.Dataset` with a ``time`` coordinate, only when
    ``request.trace_variables`` is not empty;
``fidelity`` (optional)
    the model configuration the run used (``twin.simulate``'s ``attrs["fidelity"]``).

The model must be picklable (an instance of a module-level class) so it can travel to dask workers. It should
stop by itself once ``request.wall_time_limit`` seconds have passed (returning status ``"timeout"``);
:mod:`campaigns.runner.sandbox` kills it otherwise. The rest of the contract (groups of runs, warm-up, what a run
costs, what the model adds to ``results.nc``) is the rest of :class:`RunModel`; the bench twin
(:data:`campaigns.bench.adapter.simulate_run`) and the synthetic model (:mod:`campaigns.runner.synthetic`)
implement it.

:func:`execute` wraps a call to the run function and turns *every* outcome,
including exceptions and invalid results, into a record; failures are data. A
run that returns ``"ok"`` after its wall-clock budget is recorded as
``"timeout"`` (its features discarded) when it overran its budget by more than
:func:`kill_grace`, the point where a sandbox would have killed it: with or
without process isolation, the same runs enter the statistics.
"""

from __future__ import annotations

import json
import math
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from campaigns.runner.sampling import noise_generator

#: Every status a run record can carry.
STATUSES = ("ok", "diverged", "failed", "timeout", "error", "lost")
STATUS_MEANINGS = {
    "ok": "completed; features valid",
    "diverged": "the simulation diverged (reported by the model)",
    "failed": "the model reported a failure, or a feature was missing or not finite",
    "timeout": "the run exceeded its wall-clock budget (stopped by itself or killed)",
    "error": "the run function raised, or its process died",
    "lost": "infrastructure failure (lost worker) persisted after the retries",
}



class RunModel(Protocol):
    """What the runner needs of a model: one run, a group of runs, a warm-up, what a run costs, and what the model
    adds to ``results.nc`` besides its runs' records."""

    #: Runs :meth:`run_group` takes at once (1: one run at a time).
    lanes: int
    #: Wall time of one run [s] at :attr:`typical_step` (the budget's estimate, :mod:`campaigns.runner.budget`);
    #: None: not known, the wall time is not estimated.
    typical_run_seconds: float | None
    #: The step [s] :attr:`typical_run_seconds` holds for (a spec's ``solver.dt`` scales it); None: no step.
    typical_step: float | None
    #: Samples of a kept time series before decimation.
    trace_samples: int
    #: Whether the model compiles on first use: the runner then compiles and times one run in a sandbox before the
    #: workers start, so they load the compiled code instead of compiling it each.
    compiles: bool

    def __call__(self, request: RunRequest) -> dict:
        """One run (the result keys in the module docstring)."""

    def run_group(self, requests: list[RunRequest]) -> list[dict]:
        """Several requests of one data set together (the bench twin's lock-step lanes), their results in order,
        each what ``self(request)`` returns for it alone, bit for bit. :func:`execute_group` calls it for groups of
        up to :attr:`lanes` and falls back to one run after the other if it raises."""

    def warm_up(self, request: RunRequest) -> None:
        """Load or compile what the run needs (imports, numba's compiled loop); called once per process and model
        configuration *before* the run's clock starts, so start-up is never charged to a run's budget."""

    def signals(self) -> tuple[str, ...] | None:
        """Every signal and feature a run can return (what a replay keeps), or None when the model cannot say."""

    def results_attributes(self, spec) -> dict[str, str]:
        """Global attributes the model adds to ``results.nc`` for the ``CampaignSpec`` ``spec``."""

    def margin_variables(self, spec, request_of: Callable[[int, int], RunRequest], map_chunks) -> dict:
        """Per-run variables the model adds to ``results.nc`` (``{name: (values, attrs)}``, the bench's loop
        margins), from ``request_of(dataset_index, run_index)``; ``map_chunks(function, chunks)`` maps on the
        campaign's cluster (None: in this process). Empty when the model adds none."""


#: Smallest time [s] a run may overrun its wall-clock budget before it counts as a timeout (and, in a
#: sandbox, is killed).
MIN_KILL_GRACE = 1.0
#: The grace grows with the budget: on a loaded machine a run's wall time stretches in proportion,
#: and a run that watches its own budget needs time to return its "timeout" record.
KILL_GRACE_FRACTION = 0.1


def kill_grace(budget: float) -> float:
    """Seconds past ``budget`` after which a run is a timeout (killed, in a sandbox)."""
    return max(MIN_KILL_GRACE, KILL_GRACE_FRACTION * budget)


@dataclass(frozen=True)
class RunRequest:
    """Everything one run needs; built by the driver, executed on a worker.

    Attributes
    ----------
    dataset, dataset_index, run_index
        Which run this is (indices are zero-based, in spec order).
    scene, parameters : str
        Scene and parameter-set names to load.
    conditions : dict
        Scene conditions: the data set's overrides plus sampled ``scene.*`` targets.
    parameter_values : dict
        Sampled parameter values (SI units) for ``ParameterSet.with_values``.
    root_seed : int
        The campaign's root seed; with the indices it gives :meth:`noise_rng`.
    solver : dict
        ``integrator`` and, when set, ``dt`` and ``output_dt``.
    features : tuple of str
        Features to return.
    trace_variables : tuple of str
        Time series to return (decimated by ``trace_decimation``); empty: none.
    outputs : tuple of str
        Everything any run of the campaign returns (features and trace variables), so the
        model's automatic fidelity is the same for every run of a data set.
    wall_time_limit : float
        Wall-clock budget of the run [s].
    seed_index : int or None
        The data set whose random streams the run uses (``CampaignSpec.seed_index``); ``None``: its own.
    procedure : dict
        The data set's test-procedure knobs (``twin.scenes.procedure.KNOBS``), applied to the scene before its
        conditions; empty: the scene's own profiles.
    """

    dataset: str
    dataset_index: int
    run_index: int
    scene: str
    parameters: str
    conditions: dict[str, float]
    parameter_values: dict[str, float]
    root_seed: int
    solver: dict[str, Any]
    features: tuple[str, ...]
    trace_variables: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    trace_decimation: int = 1
    wall_time_limit: float = math.inf
    seed_index: int | None = None
    procedure: dict[str, Any] = field(default_factory=dict)

    def noise_rng(self) -> np.random.Generator:
        """The run's sensor-noise generator (see :mod:`campaigns.runner.sampling`)."""
        seed_index = self.dataset_index if self.seed_index is None else self.seed_index
        return noise_generator(self.root_seed, seed_index, self.run_index)


def record(request: RunRequest, status: str, reason: str, t_reached: float, wall_time: float, features=None, trace=None,
           fidelity: str = "", integrator: str = "") -> dict:
    """The stored record of one run (``features`` default to NaN)."""
    values = {f: math.nan for f in request.features}
    values.update(features or {})
    return {
        "dataset_index": request.dataset_index,
        "run_index": request.run_index,
        "status": status,
        "failure_reason": reason,
        "t_reached": float(t_reached),
        "wall_time": float(wall_time),
        "features": values,
        "trace": trace,
        "fidelity": fidelity,
        "integrator": integrator,
    }


_warmed: set[tuple] = set()


def warm_up(run_function: RunModel, request: RunRequest) -> None:
    """Call ``run_function.warm_up(request)`` once per process and model configuration.

    A failing warm-up is ignored here: the run itself then fails and is recorded with its reason.
    """
    key = (run_function_name(run_function), request.scene, json.dumps(request.procedure, sort_keys=True),
           request.parameters,
           json.dumps(request.solver, sort_keys=True, default=str), request.outputs)
    if key in _warmed:
        return
    _warmed.add(key)
    try:
        run_function.warm_up(request)
    except Exception:  # noqa: BLE001 - reported by the run that follows
        pass


def execute(run_function: RunModel, request: RunRequest) -> dict:
    """Call ``run_function`` on ``request`` and return its record; never raises.

    The run's warm-up (:func:`warm_up`) happens before its clock starts.
    """
    warm_up(run_function, request)
    start = time.perf_counter()
    try:
        result = run_function(request)
        wall_time = time.perf_counter() - start
        return _checked(request, result, wall_time)
    except Exception as exc:  # a failing run (or a malformed result) is data; the campaign goes on
        last = traceback.extract_tb(exc.__traceback__)[-1]
        reason = f"{type(exc).__name__}: {exc} (at {last.filename}:{last.lineno})"
        return record(request, "error", reason, math.nan, time.perf_counter() - start)


def execute_group(run_function: RunModel, requests: list[RunRequest]) -> list[dict]:
    """Call ``run_function.run_group`` on ``requests`` and return one record per request, in order; never raises.

    A group's budget is the sum of its runs' budgets (it may not take longer than running them one after the
    other); each run is charged its share of the group's wall time. If the group call raises (a request the
    group cannot take, e.g. a broken parameter set), every request is executed alone (:func:`execute`) so that
    each failure is recorded with its own reason.
    """
    if len(requests) == 1 or run_function.lanes == 1:
        return [execute(run_function, request) for request in requests]
    warm_up(run_function, requests[0])
    start = time.perf_counter()
    try:
        results = run_function.run_group(requests)
    except Exception:  # noqa: BLE001 - each request is then run alone, and its own failure recorded
        return [execute(run_function, request) for request in requests]
    share = (time.perf_counter() - start) / len(requests)
    return [_checked(request, result, share) for request, result in zip(requests, results, strict=True)]


def _checked(request: RunRequest, result: dict, wall_time: float) -> dict:
    """The record of a returned result; an "ok" run without every feature finite is "failed"."""
    status = str(result.get("status", "ok"))
    reason = str(result.get("failure_reason", ""))
    features = {f: float(v) for f, v in (result.get("features") or {}).items() if f in request.features}
    if status == "ok":
        problems = [f"feature {f} missing from the run output" for f in request.features if f not in features]
        problems += [f"feature {f} is not finite ({v})" for f, v in features.items() if not math.isfinite(v)]
        if problems:
            status, reason = "failed", "; ".join(problems)
    if status not in STATUSES:
        status, reason = "error", f"run function returned unknown status {status!r}: {reason}"
    limit = request.wall_time_limit + kill_grace(request.wall_time_limit)
    if status == "ok" and wall_time > limit:
        reason = (f"ran {wall_time:.3g} s wall clock, over its {request.wall_time_limit:g} s budget + "
                  f"{limit - request.wall_time_limit:.3g} s "
                  "grace (not interruptible in this process: it ran to the end; its features are discarded)")
        return record(request, "timeout", reason, result.get("t_reached", math.nan), wall_time)
    return record(request, status, reason, result.get("t_reached", math.nan), wall_time, features, result.get("trace"),
                  str(result.get("fidelity", "")), str(result.get("integrator", "")))


def run_function_name(run_function) -> str:
    """``module:name`` of a run function defined at module level (found by identity or equality),
    else its ``repr`` (what ``results.nc`` records and :mod:`campaigns.bench.replay` resolves)."""
    module_name = getattr(run_function, "__module__", None) or type(run_function).__module__
    module = sys.modules.get(module_name)
    for name, value in vars(module).items() if module else ():
        if value is run_function or (type(value) is type(run_function) and _equal(value, run_function)):
            return f"{module_name}:{name}"
    return repr(run_function)


def _equal(a, b) -> bool:
    try:
        return bool(a == b)
    except Exception:  # noqa: BLE001 - objects without a usable equality are not the same run function
        return False
