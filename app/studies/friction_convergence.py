"""Convergence of the free-nut results in the friction laws' regularisation speed (issue 41, item 1).

The seal's Coulomb term is ``F_c(v) tanh(v / v_th)`` (twin.physics.friction.stribeck_friction) with
``v_th = pneumatics.friction_velocity_threshold``, the guides' the same law with the engine constant
``twin.engine.model.LINEAR_VELOCITY_THRESHOLD``. Below ``v_th`` the law is a viscous damper of slope
``F_c / v_th``, not stiction; a converged answer must not move when ``v_th`` is halved. Each point is a paired run
(same scene, parameters and noise seed; only ``v_th`` and, where stability needs it, the step differ) of the
thesis campaign's fidelity, RK4, the scene's full duration (the features average the whole 10 s record).

What is recorded per run: ``f_b`` and ``H`` (measured and true), and while the screw is at rest (its equivalent
position moved by less than ``twin.features.MOTION_SPEED_THRESHOLD`` over an output sample) the force loop's error
(external force minus demand: RMS) and the master nut's speed (RMS and peak), and the run's CPU time.

The step: ``v_th`` adds a real eigenvalue ``-F_s / (m v_th)`` (the regularised Coulomb slope on the moving mass: seal
400 N on the 7.5 kg piston, guides 12 N on the 8 kg master nut); RK4's real-axis reach is 2.785, so each point
runs at the largest step dividing 125 us that stays below ``STEP_MARGIN`` of that limit, and never above
``BASE_STEP`` (the step at which the default v_th is converged: docs/accuracy.md).
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from contextlib import contextmanager
from dataclasses import asdict, dataclass

import numpy as np

import twin
import twin.engine.model as engine_model
from twin.features import MOTION_SPEED_THRESHOLD

DATASETS = ("ds2", "ds4", "ds6", "ds7")
SEAL_THRESHOLDS = (5.0e-3, 2.5e-3, 1.0e-3, 0.5e-3, 0.25e-3)   # m/s, halved from the default 5 mm/s
GUIDE_THRESHOLDS = (1.0e-4, 2.0e-5, 5.0e-6)                   # m/s, from the default 1e-4 m/s
SEEDS = (0, 1, 2)
BASE_STEP = 1.5625e-5       # s: the tribologist review's step (issue 41), 1/8 of the drive period
RK4_REAL_REACH = 2.785
STEP_MARGIN = 0.5           # of RK4's real-axis limit: the friction mode is coupled to the load cell and contact
OUTPUTS = ["backlash_feature", "backlash_feature_true", "backlash_hysteresis", "backlash_hysteresis_true",
           "position_demand", "nut1_position", "screw_equivalent_position", "linear_encoder_position",
           "preload_force", "external_force", "nut1_speed", "force_demand"]


@dataclass(frozen=True)
class Point:
    """One run's result (SI units)."""

    dataset: str
    seed: int
    seal_threshold: float
    guide_threshold: float
    dt: float
    status: str
    backlash_feature: float
    backlash_feature_true: float
    backlash_hysteresis: float
    backlash_hysteresis_true: float
    force_error_rms_at_rest: float
    nut_speed_rms_at_rest: float
    nut_speed_peak_at_rest: float
    cpu_s: float


def stable_step(seal_threshold: float, guide_threshold: float, params: twin.ParameterSet) -> float:
    """The largest step ``125 us / 2^k`` below ``STEP_MARGIN`` of RK4's limit on the two friction eigenvalues."""
    v = params.value
    seal = max(v("pneumatics.friction_static"), v("pneumatics.friction_dynamic")) / (
        seal_threshold * v("pneumatics.piston_mass"))
    guides = max(v("sled.guide_friction_static"), v("sled.guide_friction_dynamic")) / (
        guide_threshold * v("sled.master_mass"))
    limit = STEP_MARGIN * RK4_REAL_REACH / max(seal, guides)
    dt = BASE_STEP
    while dt > limit:
        dt /= 2.0
    return dt


@contextmanager
def guide_threshold_set(value: float):
    """The guides' regularisation speed is an engine constant, not a parameter: set it for the runs inside."""
    saved = engine_model.LINEAR_VELOCITY_THRESHOLD
    engine_model.LINEAR_VELOCITY_THRESHOLD = value
    try:
        yield
    finally:
        engine_model.LINEAR_VELOCITY_THRESHOLD = saved


def at_rest_figures(ds) -> tuple[float, float, float]:
    """RMS force-loop error, RMS and peak master-nut speed over the samples where the screw is at rest."""
    screw = ds.screw_equivalent_position.values
    dt = float(ds.time.values[1] - ds.time.values[0])
    rest = np.abs(np.diff(screw, prepend=screw[0])) < MOTION_SPEED_THRESHOLD * dt
    error = (ds.external_force.values - ds.force_demand.values)[rest]
    speed = ds.nut1_speed.values[rest]
    return float(np.sqrt(np.mean(error ** 2))), float(np.sqrt(np.mean(speed ** 2))), float(np.max(np.abs(speed)))


def run_point(dataset: str, seed: int, seal_threshold: float, guide_threshold: float,
              params: twin.ParameterSet, dt: float | None = None, duration: float | None = None) -> Point:
    """One paired run; ``dt`` defaults to :func:`stable_step`."""
    dt = stable_step(seal_threshold, guide_threshold, params) if dt is None else dt
    varied = params.with_values({"pneumatics.friction_velocity_threshold": seal_threshold})
    start = time.process_time()
    with guide_threshold_set(guide_threshold):
        ds = twin.simulate(dataset, varied, solver=twin.Solver(dt=dt), rng=seed, duration=duration, outputs=OUTPUTS,
                           throw=False)
    cpu = time.process_time() - start
    ok = ds.attrs["status"] == "ok"
    rest = at_rest_figures(ds) if ok else (math.nan,) * 3
    feature = {name: float(ds[name]) if ok else math.nan for name in OUTPUTS[:4]}
    return Point(dataset, seed, seal_threshold, guide_threshold, dt, ds.attrs["status"], **feature,
                 force_error_rms_at_rest=rest[0], nut_speed_rms_at_rest=rest[1], nut_speed_peak_at_rest=rest[2],
                 cpu_s=cpu)


def study_plan(datasets: Iterable[str] = DATASETS, seeds: Iterable[int] = SEEDS,
               seal_thresholds: Iterable[float] = SEAL_THRESHOLDS,
               guide_thresholds: Iterable[float] = GUIDE_THRESHOLDS) -> list[tuple[str, int, float, float]]:
    """The seal sweep of every data set at the default guides, then the guide sweep at the default seal (no
    duplicate of the shared default point): the order in which a study interrupted by its time budget is complete."""
    seal_default = twin.load_parameters().value("pneumatics.friction_velocity_threshold")
    guide_default = engine_model.LINEAR_VELOCITY_THRESHOLD
    datasets, seeds = list(datasets), list(seeds)
    seal = [(name, seed, s, guide_default) for name in datasets for s in seal_thresholds for seed in seeds]
    guides = [(name, seed, seal_default, g) for name in datasets for g in guide_thresholds if g != guide_default
              for seed in seeds]
    return seal + guides


def as_rows(points: Iterable[Point]) -> list[dict]:
    return [asdict(p) for p in points]
