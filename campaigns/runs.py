"""One run: the request a run function receives and the outcome recorded for it.

The run-function contract is ``run_function(request: RunRequest) -> dict`` with
keys

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

The function must be picklable (a module-level function or an instance of a
module-level class) so it can travel to dask workers. It should stop by itself
once ``request.wall_time_limit`` seconds have passed (returning status
``"timeout"``); :mod:`campaigns.sandbox` kills it otherwise.

:func:`execute` wraps a call to the run function and turns *every* outcome,
including exceptions and invalid results, into a record; failures are data.
"""

from __future__ import annotations

import math
import time
import traceback
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from campaigns.sampling import noise_generator

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

RunFunction = Callable[["RunRequest"], dict]


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

    def noise_rng(self) -> np.random.Generator:
        """The run's sensor-noise generator (see :mod:`campaigns.sampling`)."""
        return noise_generator(self.root_seed, self.dataset_index, self.run_index)


def record(request: RunRequest, status: str, reason: str, t_reached: float, wall_time: float, features=None, trace=None,
           fidelity: str = "") -> dict:
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
    }


def execute(run_function: RunFunction, request: RunRequest) -> dict:
    """Call ``run_function`` on ``request`` and return its record; never raises."""
    start = time.perf_counter()
    try:
        result = run_function(request)
        wall_time = time.perf_counter() - start
        return _checked(request, result, wall_time)
    except Exception as exc:  # a failing run (or a malformed result) is data; the campaign goes on
        last = traceback.extract_tb(exc.__traceback__)[-1]
        reason = f"{type(exc).__name__}: {exc} (at {last.filename}:{last.lineno})"
        return record(request, "error", reason, math.nan, time.perf_counter() - start)


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
    return record(request, status, reason, result.get("t_reached", math.nan), wall_time, features, result.get("trace"),
                  str(result.get("fidelity", "")))
