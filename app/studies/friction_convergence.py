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

Two more studies of issue 41 live here. :func:`paired_study` is the acceptance evidence of its "done when": the
thesis campaign's own sampled runs under several arms (the elasto-plastic seal at the campaign step and at half of
it, the regularised seal at ``v_th`` and ``v_th / 2``, the presliding stiffness at the ends of its range, the
guides' ``v_th`` halved), judged pair by pair by :func:`paired_shifts` with the accuracy rule's mean-shift verdict.
:func:`free_nut_study` is item 4: traces of the free nut with the screw at rest, with and without the load cell's
noise, and the nut's contact oscillation, read by :func:`rest_figures` and :func:`contact_oscillation`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from contextlib import contextmanager
from dataclasses import asdict, dataclass, replace

import numpy as np
import xarray as xr

import twin
import twin.engine.model as engine_model
from twin.features import MOTION_SPEED_THRESHOLD
from twin.solver import split_solver

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


# --- The acceptance evidence (issue 41, "done when"): paired runs of the thesis campaign's own sampled runs ---------
#
# Run i of a data set has the thesis spec's sampled Table 9.5 parameters and its noise stream under every arm
# (campaigns.runner.sampling, build_request), so an arm's paired difference is its configuration's effect alone. The
# runs go through twin.simulate_batch's lock-step lanes (the same numbers as each run alone). An arm changes the
# solver's step (a factor of the campaign's own default step for the arm's fidelity), the seal's friction level and
# parameter values, or the guides' regularisation speed; everything else is the campaign's request.

ACCEPTANCE_DATASETS = ("ds2", "ds4", "ds6", "ds7")
ACCEPTANCE_FEATURES = ("backlash_feature", "backlash_hysteresis", "backlash_feature_true", "backlash_hysteresis_true")
#: The issue's criterion: at least this many pairs per data set (the rule's 200 are for the sd ratio and rankings).
ACCEPTANCE_PAIRS = 30


@dataclass(frozen=True)
class Arm:
    """One configuration of the paired study (SI units): the seal's friction level, a factor on the campaign's
    default step, parameter values over the run's own, and the guides' regularisation speed (None: the engine's)."""

    name: str
    seal_friction: str = "regularised"
    step_factor: float = 1.0
    parameters: tuple[tuple[str, float], ...] = ()
    guide_threshold: float | None = None


def presliding_stiffness_values(stiffness: float, params: twin.ParameterSet) -> tuple[tuple[str, float], ...]:
    """``sigma_0`` and the ``sigma_1 = 2 zeta sqrt(sigma_0 m_p)`` that keeps the nominal damping ratio of the
    presliding mode (pneumatics.toml, friction_bristle_damping): the sensitivity moves the stiffness, not the
    damping ratio."""
    v = params.value
    ratio = v("pneumatics.friction_bristle_damping") / (
        2.0 * math.sqrt(v("pneumatics.friction_presliding_stiffness") * v("pneumatics.piston_mass")))
    damping = 2.0 * ratio * math.sqrt(stiffness * v("pneumatics.piston_mass"))
    return (("pneumatics.friction_presliding_stiffness", stiffness), ("pneumatics.friction_bristle_damping", damping))


def acceptance_arms(params: twin.ParameterSet) -> tuple[Arm, ...]:
    """The arms of the acceptance study: the elasto-plastic seal at the campaign step and at half of it; the
    regularised seal at 5 and 2.5 mm/s (same step); the presliding stiffness at the ends of its range; the guides'
    regularisation halved under the elasto-plastic seal at the half step (stable for it: ``stable_step``)."""
    v_th = params.value("pneumatics.friction_velocity_threshold")
    guides = engine_model.LINEAR_VELOCITY_THRESHOLD
    ep = "elasto_plastic"
    return (
        Arm("elasto_plastic", ep),
        Arm("elasto_plastic_half_step", ep, 0.5),
        Arm("regularised", "regularised"),
        Arm("regularised_half_v_th", "regularised", parameters=(("pneumatics.friction_velocity_threshold",
                                                                 v_th / 2.0),)),
        Arm("elasto_plastic_sigma0_2e6", ep, parameters=presliding_stiffness_values(2.0e6, params)),
        Arm("elasto_plastic_sigma0_4e7", ep, parameters=presliding_stiffness_values(4.0e7, params)),
        Arm("elasto_plastic_half_step_half_guide_v_th", ep, 0.5, guide_threshold=guides / 2.0),
    )


#: (candidate, reference, what the difference measures): the numerical halvings first, then the physics.
ACCEPTANCE_PAIRINGS = (
    ("elasto_plastic_half_step", "elasto_plastic", "elasto-plastic seal: step halved"),
    ("regularised_half_v_th", "regularised", "regularised seal: v_th 5 -> 2.5 mm/s"),
    ("elasto_plastic_half_step_half_guide_v_th", "elasto_plastic_half_step",
     "guides: v_th 1e-4 -> 5e-5 m/s (elasto-plastic seal, half step)"),
    ("elasto_plastic", "regularised", "law: elasto-plastic minus regularised (5 mm/s)"),
    ("elasto_plastic_sigma0_2e6", "elasto_plastic", "sigma_0 1e7 -> 2e6 N/m"),
    ("elasto_plastic_sigma0_4e7", "elasto_plastic", "sigma_0 1e7 -> 4e7 N/m"),
)


def thesis_requests(datasets: Iterable[str], runs: Iterable[int], spec_path=None):
    """The thesis campaign's requests of ``runs`` of ``datasets`` (:func:`campaigns.runner.execution.build_request`
    on the spec's own sampled values, untraced): what the campaign would run."""
    from campaigns.bench.campaign import load_spec
    from campaigns.bench.solver_accuracy import THESIS_SPEC  # lazy: the campaign runner loads only for this study
    from campaigns.runner.execution import build_request
    from campaigns.runner.sampling import sample_run

    spec = load_spec(THESIS_SPEC if spec_path is None else spec_path)
    names = [d.name for d in spec.datasets]
    distributions = spec.distributions()
    targets = [d.target for d in distributions]
    requests = []
    for name in datasets:
        d = names.index(name)
        for run in runs:
            values = sample_run(distributions, spec.root_seed, spec.seed_index(d), run, spec.fixed_columns(d, targets),
                                **spec.unit_draws(run, targets))
            samples = np.broadcast_to(values, (len(names), run + 1, len(values)))  # only [d, run] is read
            requests.append(build_request(spec, samples, d, run, targets=targets))
    return requests


def _arm_fidelity(request_fidelity, seal_friction: str):
    levels = {"default": request_fidelity} if isinstance(request_fidelity, str) else dict(request_fidelity)
    return {**levels, "seal_friction": seal_friction}


def run_arm(arm: Arm, requests, lanes: int = 8) -> dict:
    """The arm's runs of ``requests`` (all of one data set, one lane group per ``lanes`` runs): per run the
    features, status and step, and the arm's process CPU per run."""
    from campaigns.bench.adapter import run_scene

    first = requests[0]
    options = {k: v for k, v in first.solver.items() if v is not None}
    options["fidelity"] = _arm_fidelity(options.get("fidelity", "auto"), arm.seal_friction)
    base = twin.load_parameters(first.parameters)
    runs = [(run_scene(r), base.with_values({**r.parameter_values, **dict(arm.parameters)}), r.noise_rng())
            for r in requests]
    guides = engine_model.LINEAR_VELOCITY_THRESHOLD if arm.guide_threshold is None else arm.guide_threshold
    with guide_threshold_set(guides):
        solver, options = split_solver(options)
        step = twin.simulate(runs[0][0], runs[0][1], solver=solver, save="features", duration=0.01, throw=False,
                             outputs=list(first.outputs), **options).dt   # the campaign's default step at this fidelity
        solver = replace(solver, dt=step * arm.step_factor, lanes=lanes)
        start = time.process_time()
        summaries = twin.simulate_batch(runs, solver=solver, throw=False, outputs=list(first.outputs), **options)
        cpu = time.process_time() - start
    return {"features": {f: [s.features.get(f, math.nan) for s in summaries] for f in ACCEPTANCE_FEATURES},
            "status": [s.status for s in summaries], "dt": [s.dt for s in summaries], "cpu_per_run": cpu / len(runs)}


def paired_study(arms: Iterable[Arm], datasets: Iterable[str] = ACCEPTANCE_DATASETS,
                 runs: Iterable[int] = range(ACCEPTANCE_PAIRS), *, lanes: int = 8, spec_path=None,
                 progress=print) -> xr.Dataset:
    """Every arm on the thesis campaign's ``runs`` of ``datasets``: features [m], status, step and CPU [s] per
    (arm, data set, run) (the CPU: the process time of the arm's lane groups shared equally by their runs)."""
    arms, datasets, runs = list(arms), list(datasets), list(runs)
    shape = (len(arms), len(datasets), len(runs))
    data = {f: np.full(shape, math.nan) for f in ACCEPTANCE_FEATURES}
    status = np.full(shape, "", dtype=object)
    dt = np.full(shape, math.nan)
    cpu = np.full(shape, math.nan)
    for j, name in enumerate(datasets):
        requests = thesis_requests([name], runs, spec_path)
        for i, arm in enumerate(arms):
            result = run_arm(arm, requests, lanes)
            for f in ACCEPTANCE_FEATURES:
                data[f][i, j] = result["features"][f]
            status[i, j], dt[i, j], cpu[i, j] = result["status"], result["dt"], result["cpu_per_run"]
            progress(f"{name} {arm.name}: {len(runs)} runs at dt {dt[i, j, 0] * 1e6:g} us, "
                     f"{sum(s == 'ok' for s in status[i, j])} ok, {result['cpu_per_run']:.2f} s CPU per run")
    coords = {"arm": [a.name for a in arms], "dataset": datasets, "run": runs}
    out = xr.Dataset({f: (("arm", "dataset", "run"), data[f], {"units": "m"}) for f in ACCEPTANCE_FEATURES},
                     coords=coords)
    out["status"] = (("arm", "dataset", "run"), status.astype(str))
    out["dt"] = (("arm", "dataset", "run"), dt, {"units": "s"})
    out["cpu_per_run"] = (("arm", "dataset", "run"), cpu, {"units": "s", "long_name": "process CPU per run in lanes: "
                                                                                "its lane groups' over their runs"})
    return out


def paired_shifts(study, pairings=ACCEPTANCE_PAIRINGS, features=ACCEPTANCE_FEATURES,
                  min_pairs: int = ACCEPTANCE_PAIRS):
    """Per pairing, data set and feature: the mean paired shift (candidate - reference) with its 95 % Student-t
    interval and the accuracy rule's verdict on ±0.05 um (:func:`campaigns.statistics.accuracy_rule.
    mean_shift_verdict`, at ``min_pairs``), over the runs both arms completed."""
    from campaigns.statistics.accuracy_rule import mean_shift_verdict

    present = [p for p in pairings if p[0] in study.arm and p[1] in study.arm]
    shape = (len(present), study.sizes["dataset"], len(features))
    figures = {k: np.full(shape, math.nan) for k in ("mean", "lower", "upper", "sd")}
    n = np.zeros(shape, dtype=int)
    verdict = np.full(shape, "", dtype=object)
    for i, (cand, ref, _) in enumerate(present):
        ok = (study.status.sel(arm=cand) == "ok") & (study.status.sel(arm=ref) == "ok")
        for j, name in enumerate(study.dataset.values):
            for k, f in enumerate(features):
                d = (study[f].sel(arm=cand, dataset=name) - study[f].sel(arm=ref, dataset=name))
                d = d.where(ok.sel(dataset=name), drop=True).values
                v = mean_shift_verdict(d, min_pairs=min_pairs)
                figures["mean"][i, j, k], figures["lower"][i, j, k], figures["upper"][i, j, k] = (
                    v.estimate, v.lower, v.upper)
                figures["sd"][i, j, k] = float(np.std(d, ddof=1)) if d.size > 1 else math.nan
                n[i, j, k], verdict[i, j, k] = d.size, v.verdict
    dims = ("pairing", "dataset", "feature")
    out = xr.Dataset({k: (dims, a, {"units": "m"}) for k, a in figures.items()},
                     coords={"pairing": [p[0] for p in present], "dataset": study.dataset.values,
                             "feature": list(features)})
    out["n"] = (dims, n)
    out["verdict"] = (dims, verdict.astype(str))
    out["reference"] = ("pairing", [p[1] for p in present])
    out["description"] = ("pairing", [p[2] for p in present])
    return out


# --- The free nut under the elasto-plastic seal (issue 41, item 4): hold, creep or hunt, from traces --------------

#: What a free-nut trace records: the nut against the screw, the piston, the force loop, the nut's contact force.
TRACE_OUTPUTS = ["position_demand", "nut1_position", "screw_equivalent_position", "piston_position",
                 "external_force", "force_demand", "nut1_contact_force", "backlash_feature", "backlash_hysteresis"]
TRACE_SPACING = 1.25e-4     # s: the drive period, 8 samples per period of the 255 Hz contact oscillation's 4 ms
#: s: the longest stretch with the screw at rest in every force-free scene (after the 5.5 s move's settling, before
#: the 6.5 s move): where the loop's behaviour with nothing moving it is read.
REST_WINDOW = (5.75, 6.45)
OSCILLATION_WINDOW = 0.4    # s: the length of the most active stretch searched for the contact oscillation
HIGH_PASS_SAMPLES = 41      # moving average removed: 5.1 ms at 125 us, a high-pass at ~195 Hz


def free_nut_trace(dataset: str, seal_friction: str, dt: float, *, seed: int = 0, quiet: bool = False,
                   params: twin.ParameterSet | None = None) -> xr.Dataset:
    """One run's trace at :data:`TRACE_SPACING`: nominal parameters, noise seed ``seed``; ``quiet`` makes the analog
    sensors ideal (no load-cell noise in the force loop), the test whether a motion is self-sustained or driven."""
    fidelity = {"seal_friction": seal_friction, **({"analog_sensors": "ideal"} if quiet else {})}
    return twin.simulate(dataset, params, rng=seed, dt=dt, output_dt=TRACE_SPACING, fidelity=fidelity,
                         outputs=TRACE_OUTPUTS)


def rest_figures(trace: xr.Dataset, window: tuple[float, float] = REST_WINDOW) -> dict[str, float]:
    """Over ``window`` (the screw at rest): the nut's motion against the screw (peak to peak [m]) and its period
    [s] (the autocorrelation's first peak beyond 20 ms holding 0.3 of the variance, NaN without one), the
    force-loop error (RMS and peak to peak [N]) and the piston's speed (RMS [m/s]; 0 when the seal holds it)."""
    t = trace.time.values
    step = float(t[1] - t[0])
    inside = (t > window[0]) & (t < window[1])
    rel = (trace.nut1_position - trace.screw_equivalent_position).values[inside]
    error = (trace.external_force - trace.force_demand).values[inside]
    speed = np.gradient(trace.piston_position.values, step)[inside]
    x = rel - rel.mean()
    correlation = np.correlate(x, x, "full")[x.size - 1:]
    lags = np.arange(correlation.size) * step
    beyond = lags > 0.02
    # the first local maximum beyond 20 ms that holds at least 0.3 of the variance: a repeating motion's period
    peaks = np.flatnonzero(beyond[1:-1] & (correlation[1:-1] > correlation[:-2])
                           & (correlation[1:-1] >= correlation[2:]) & (correlation[1:-1] > 0.3 * correlation[0])) + 1
    k = int(peaks[0]) if peaks.size else 0
    k_is_peak = peaks.size > 0
    return {"nut_peak_to_peak": float(np.ptp(rel)), "period": float(lags[k]) if k_is_peak else math.nan,
            "force_error_rms": float(np.sqrt(np.mean(error ** 2))), "force_error_peak_to_peak": float(np.ptp(error)),
            "piston_speed_rms": float(np.sqrt(np.mean(speed ** 2)))}


def contact_oscillation(trace: xr.Dataset) -> dict[str, float]:
    """The nut's contact force in its most active :data:`OSCILLATION_WINDOW` (largest RMS after removing a
    :data:`HIGH_PASS_SAMPLES` moving average): that RMS [N], the window's peak to peak [N], its start [s] and the
    frequency of its spectral peak [Hz]."""
    t, force = trace.time.values, trace.nut1_contact_force.values
    step = float(t[1] - t[0])
    length = int(round(OSCILLATION_WINDOW / step))
    kernel = np.ones(HIGH_PASS_SAMPLES) / HIGH_PASS_SAMPLES
    best = (-1.0, 0)
    for start in range(0, force.size - length, length // 2):
        piece = force[start:start + length]
        rms = float(np.sqrt(np.mean((piece - np.convolve(piece, kernel, "same"))[HIGH_PASS_SAMPLES:-HIGH_PASS_SAMPLES]
                                    ** 2)))
        best = max(best, (rms, start))
    rms, start = best
    piece = force[start:start + length]
    high = piece - np.convolve(piece, kernel, "same")
    spectrum = np.abs(np.fft.rfft(high * np.hanning(high.size)))
    frequencies = np.fft.rfftfreq(high.size, step)
    lowest = int(np.searchsorted(frequencies, 20.0))
    return {"rms": rms, "peak_to_peak": float(np.ptp(piece)), "start": float(t[start]),
            "frequency": float(frequencies[lowest + int(np.argmax(spectrum[lowest:]))])}


@dataclass(frozen=True)
class TraceCase:
    """One free-nut trace of the item-4 study: scene, seal law, step, quiet (no load-cell noise), parameter values."""

    dataset: str
    seal_friction: str
    dt: float
    quiet: bool = False
    parameters: tuple[tuple[str, float], ...] = ()

    @property
    def label(self) -> str:
        extra = "".join(f", {k.split('.')[-1]} = {v:g}" for k, v in self.parameters)
        return (f"{self.dataset} {self.seal_friction} {self.dt * 1e6:g} us{', quiet' if self.quiet else ''}"
                f"{extra}")


#: The traces behind docs/model.md's "The free nut under the elasto-plastic seal": each law at three steps on ds4
#: (the contact oscillation) and ds2 quiet (the limit cycle), with the noise and without, and the regularised law
#: without its Stribeck drop (F_s = F_d) to name the oscillation's cause.
FREE_NUT_CASES = (
    *(TraceCase("ds4", "elasto_plastic", dt) for dt in (6.25e-5, 3.125e-5, 1.5625e-5)),
    *(TraceCase("ds4", "regularised", dt) for dt in (6.25e-5, 1.5625e-5)),
    TraceCase("ds4", "regularised", 1.5625e-5, parameters=(("pneumatics.friction_static", 250.0),)),
    TraceCase("ds4", "elasto_plastic", 3.125e-5, quiet=True),
    TraceCase("ds4", "regularised", 3.125e-5, quiet=True),
    *(TraceCase("ds2", "elasto_plastic", dt, quiet=True) for dt in (6.25e-5, 3.125e-5, 1.5625e-5)),
    TraceCase("ds2", "regularised", 3.125e-5, quiet=True),
    TraceCase("ds2", "elasto_plastic", 3.125e-5),
    TraceCase("ds2", "regularised", 3.125e-5),
)


def free_nut_study(cases=FREE_NUT_CASES, progress=print) -> tuple[list[dict], dict[str, xr.Dataset]]:
    """Every case's :func:`rest_figures` and :func:`contact_oscillation` (SI units) with its features and CPU, and
    the traces by label."""
    base = twin.load_parameters()
    rows, traces = [], {}
    for case in cases:
        start = time.process_time()
        trace = free_nut_trace(case.dataset, case.seal_friction, case.dt, quiet=case.quiet,
                               params=base.with_values(dict(case.parameters)))
        cpu = time.process_time() - start
        row = {"label": case.label, **{f"rest_{k}": v for k, v in rest_figures(trace).items()},
               **{f"contact_{k}": v for k, v in contact_oscillation(trace).items()},
               "backlash_feature": float(trace.backlash_feature),
               "backlash_hysteresis": float(trace.backlash_hysteresis), "cpu_s": cpu}
        rows.append(row)
        traces[case.label] = trace
        progress(f"{case.label}: {cpu:.1f} s CPU")
    return rows, traces
