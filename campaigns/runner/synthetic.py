"""A fast synthetic model with known dependences, for tests and benchmarks.

It lives in the package (not under ``tests/``) so dask workers and sandbox
processes can import it like any run function. Its features depend
monotonically, with a known ranking of strength, on the sampled values:

``backlash_feature_true = backlash + (preload + external_force) / synthetic.stiffness``

``backlash_feature = synthetic.gain * backlash_feature_true + synthetic.offset
+ TEMPERATURE_SLOPE * (room_temperature - 298.15 K) + noise``

with ``noise ~ N(0, NOISE_SIGMA)`` from the run's noise generator, and
``synthetic.inert`` having no effect. A run with a test procedure (``RunRequest.procedure``) scales the backlash
term and the noise by :func:`procedure_effect`. Faults can be injected into chosen runs.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import xarray as xr

from campaigns.runner.catalog import StaticCatalog
from campaigns.runner.runs import RunRequest

NOISE_SIGMA = 0.2e-6
TEMPERATURE_SLOPE = 0.05e-6
#: The synthetic model's procedure effect (:func:`procedure_effect`): preload [N] and external force [N] scales.
PROCEDURE_PRELOAD_SCALE = 500.0
PROCEDURE_FORCE_SCALE = 1000.0

SYNTHETIC_CATALOG = StaticCatalog(
    parameters={
        "synthetic.gain": (1.0, "1"),
        "synthetic.offset": (0.0, "m"),
        "synthetic.stiffness": (2.0e8, "N/m"),
        "synthetic.inert": (3.0, "1"),
    },
    conditions={"backlash": (0.0, "m"), "preload": (0.0, "N"), "external_force": (0.0, "N"),
                "room_temperature": (298.15, "K"), "supply_pressure": (6e5, "Pa")},
    scene_names=("nominal", "ds1", "ds2", "ds3", "ds4", "ds5", "ds6", "ds7"),
    feature_units={
        "backlash_feature": ("m", "synthetic measured backlash feature"),
        "backlash_feature_true": ("m", "synthetic true backlash feature"),
    },
)


@dataclass(frozen=True)
class SyntheticModel:
    """The synthetic model as a run model (:class:`campaigns.runner.runs.RunModel`), picklable.

    Parameters
    ----------
    faults : dict, optional
        ``{(dataset_name, run_index): kind}`` with kind ``"raise"`` (exception),
        ``"nan"`` (a NaN feature), ``"diverge"`` (status diverged), ``"hang"``
        (sleeps far past ``wall_time_limit``, ignoring it, as a stuck compiled
        loop would) or ``"crash"`` (the process exits at once, as on a segfault).
    delay : float, default 0
        Seconds each run sleeps (to emulate compute time).
    log_dir : str, optional
        If set, each executed run appends ``"<dataset> <run>"`` to
        ``<log_dir>/runs-<pid>.log`` (counts executions across processes).
    """

    faults: dict = field(default_factory=dict)
    delay: float = 0.0
    log_dir: str | None = None
    #: One run at a time; its cost is not known (the wall time is not estimated); no compilation.
    lanes: ClassVar[int] = 1
    typical_run_seconds: ClassVar[float | None] = None
    typical_step: ClassVar[float | None] = None
    #: Samples of a kept time series (:func:`_trace`).
    trace_samples: ClassVar[int] = 11
    compiles: ClassVar[bool] = False

    def run_group(self, requests: list[RunRequest]) -> list[dict]:
        """One run after the other (``lanes`` is 1: never called with more than one)."""
        return [self(request) for request in requests]

    def signals(self) -> None:
        """The synthetic model does not list its signals: a replay keeps the spec's trace variables."""
        return None

    def results_attributes(self, spec) -> dict[str, str]:
        return {}

    def margin_variables(self, spec, request_of, map_chunks) -> dict:
        return {}

    def warm_up(self, request: RunRequest) -> None:
        """One fault-free, unlogged run: the first xarray objects of a fresh process are slow to build
        (lazy imports), and that start-up must not be charged to the first real run."""
        SyntheticModel()(request)

    def __call__(self, request: RunRequest) -> dict:
        if self.log_dir is not None:
            with open(os.path.join(self.log_dir, f"runs-{os.getpid()}.log"), "a") as f:
                f.write(f"{request.dataset} {request.run_index}\n")
        if self.delay:
            time.sleep(self.delay)
        fault = self.faults.get((request.dataset, request.run_index))
        if fault == "raise":
            raise RuntimeError("injected failure")
        if fault == "hang":
            time.sleep(request.wall_time_limit + 3600.0)
        if fault == "crash":
            os._exit(3)
        values = {name: value for name, (value, _) in SYNTHETIC_CATALOG.conditions.items()}
        values.update({k: v for k, v in request.procedure.items() if k in values})
        values.update(request.conditions)
        params = {name: value for name, (value, _) in SYNTHETIC_CATALOG.parameters.items()}
        params.update(request.parameter_values)
        sensitivity, noise_scale = procedure_effect(request.procedure)
        true = (sensitivity * values["backlash"]
                + (values["preload"] + values["external_force"]) / params["synthetic.stiffness"])
        measured = (
            params["synthetic.gain"] * true
            + params["synthetic.offset"]
            + TEMPERATURE_SLOPE * (values["room_temperature"] - 298.15)
            + request.noise_rng().normal(0.0, NOISE_SIGMA * noise_scale)
        )
        if fault == "nan":
            measured = math.nan
        return {
            "status": "diverged" if fault == "diverge" else "ok",
            "failure_reason": "injected divergence" if fault == "diverge" else "",
            "t_reached": 0.5 if fault == "diverge" else 1.0,
            "features": {"backlash_feature": measured, "backlash_feature_true": true},
            "trace": _trace(true, measured) if request.trace_variables else None,
        }


def procedure_effect(knobs: dict) -> tuple[float, float]:
    """The synthetic model's answer to a test procedure (:mod:`twin.scenes.procedure` knobs), with a known best:
    the backlash term is scaled by ``exp(-preload / PROCEDURE_PRELOAD_SCALE)`` (a preload hides the play) and the
    noise by ``(1 + |external_force| / PROCEDURE_FORCE_SCALE) / sqrt(cycles / 4)`` (a load disturbs, cycles average).
    No procedure: ``(1, 1)``."""
    if not knobs:
        return 1.0, 1.0
    sensitivity = math.exp(-float(knobs.get("preload", 0.0)) / PROCEDURE_PRELOAD_SCALE)
    noise = (1.0 + abs(float(knobs.get("external_force", 0.0))) / PROCEDURE_FORCE_SCALE) / math.sqrt(
        float(knobs.get("cycles", 4)) / 4.0)
    return sensitivity, noise


def _trace(true: float, measured: float) -> xr.Dataset:
    t = np.linspace(0.0, 1.0, 11)
    return xr.Dataset(
        {"nut1_position": ("time", true * t, {"units": "m"}), "motor_current": ("time", measured * t, {"units": "A"})},
        coords={"time": t},
    )


synthetic_run = SyntheticModel()
