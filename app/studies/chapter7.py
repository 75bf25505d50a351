"""Validation of the free nut against the thesis's Ch. 7 backlash results (Sec. 7.9.3, Figs. 7.16-7.19).

Ch. 7 is a multibody model of the screw (one nut body on an ideal prismatic joint, the screw on an ideal revolute
joint, a speed PI loop on a motor transfer function); BenchTwin is the lumped bench of Ch. 9 (a motor, cascaded PI
loops, two nuts on the sled, a pneumatic cylinder). The study runs the thesis's stated conditions as the scenes
``chapter7_backlash`` (0.05 mm, no preload, no force), ``chapter7_backlash_300um`` (Fig. 7.18) and
``chapter7_backlash_force`` (1 kN from 0.25 s), with the thesis's support friction (Sec. 7.9.3: 100 N static,
70 N dynamic in total), and measures what the thesis shows at each speed reversal: how long the nut stops, how
long both contact forces vanish, how far the screw turns meanwhile, the support-friction peak, and the width of
the nut-screw loop against the backlash. Fig. 7.19 (preload against nut displacement, screw fixed) is the static
contact law of Eq. 9.4 with Hertz (:func:`preload_curve`) beside its closed form at the design angle.
docs/validation.md, "Validation of the free nut against the thesis's Chapter 7" reads the numbers.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (backend must be chosen first)
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

import twin  # noqa: E402
from app.studies.charts import save_png  # noqa: E402
from twin.engine.model import LINEAR_VELOCITY_THRESHOLD, build_model, contact_force  # noqa: E402
from twin.fidelity import resolve_fidelity  # noqa: E402
from twin.layout import K  # noqa: E402
from twin.physics import hertz  # noqa: E402
from twin.physics.ball_screw import (  # noqa: E402
    CONTACT_CONSTANT_ANGLE,
    CONTACT_VARIABLE_ANGLE,
    contact_geometry,
    effective_loaded_balls,
    groove_centre_distance,
    helix_angle,
)
from twin.physics.friction import stribeck_friction  # noqa: E402
from twin.scenes import load_scene  # noqa: E402

FIGURE_DPI = 100  # the resolution of the study's PNG figures

#: The thesis's scenes of Sec. 7.9.3 (twin/scenes/library/chapter7_*.toml).
SCENES = ("chapter7_backlash", "chapter7_backlash_300um", "chapter7_backlash_force")
#: Sec. 7.9.3: "a total static and dynamic friction of 100 [N] and 70 [N]" of the supports (Eq. 7.63).
SUPPORT_FRICTION_STATIC = 100.0
SUPPORT_FRICTION_DYNAMIC = 70.0
#: Recording step [s]: two drive periods, so a stop of a few ms spans tens of samples.
OUTPUT_DT = 2.5e-4
#: The nut counts as stopped below this speed [m/s]: five times the guides' friction regularisation speed
#: (``LINEAR_VELOCITY_THRESHOLD``), inside which the regularised Coulomb force brings the free nut to rest.
STOP_SPEED = 5.0 * LINEAR_VELOCITY_THRESHOLD
#: Both contacts count as unloaded below this axial force [N]: far below the 70 N the supports need to move the
#: nut, far above the contact damping's residue at a closed flank.
FORCE_FREE = 1.0
#: Half-window around a reversal of the screw [s]: a quarter of the 5 Hz period, so windows never overlap.
WINDOW = 0.05
#: The loop's plateaus are read where the screw moves faster than this [m/s]: a quarter of the 41.7 mm/s peak,
#: past the impact transient of each reversal.
MOVING_SPEED = 10.0e-3
#: The external force's smooth rise in ``chapter7_backlash_force`` [s] (Sec. 7.9.3: "from 0.25 to 0.3 [s]").
FORCE_START, FORCE_END = 0.25, 0.3


def support_friction(params) -> dict[str, float]:
    """Guide-friction overrides giving the thesis's total support friction: the twin's master nut carries
    ``1 / (1 + slave_friction_fraction)`` of the sled's guide friction, its slave the rest (``sled.toml``)."""
    master_share = 1.0 / (1.0 + params.value("sled.slave_friction_fraction"))
    return {"sled.guide_friction_static": SUPPORT_FRICTION_STATIC * master_share,
            "sled.guide_friction_dynamic": SUPPORT_FRICTION_DYNAMIC * master_share}


def backlash_run(scene: str, params=None) -> xr.Dataset:
    """One Sec. 7.9.3 scene with the thesis's support friction and ideal instruments (the thesis shows true
    positions): the twin's signals, plus ``screw_speed`` and the master nut's ``guide_friction`` [N] (Eq. 7.63
    evaluated on the nut's speed with the run's parameters)."""
    params = params if params is not None else twin.load_parameters("bench")
    params = params.with_values(support_friction(params))
    ds = twin.simulate(load_scene(scene), params, rng=0, output_dt=OUTPUT_DT,
                       fidelity={"encoders": "ideal", "analog_sensors": "ideal"})
    t = ds.time.values
    screw_speed = np.gradient(ds.screw_equivalent_position.values, t)
    guide = [stribeck_friction(v, params.value("sled.guide_friction_static"),
                               params.value("sled.guide_friction_dynamic"),
                               params.value("sled.guide_friction_stribeck_rate"),
                               params.value("sled.guide_viscous_friction"), LINEAR_VELOCITY_THRESHOLD)
             for v in ds.nut1_speed.values.tolist()]
    return ds.assign(screw_speed=("time", screw_speed, {"units": "m/s"}),
                     guide_friction=("time", np.array(guide), {"units": "N"}))


def reversal_times(ds: xr.Dataset) -> np.ndarray:
    """Instants where the screw's speed changes sign [s], one per reversal (crossings within ``WINDOW`` of the
    previous one, the impact's ripple, are the same reversal)."""
    v, t = ds.screw_speed.values, ds.time.values
    crossings = t[1:][np.signbit(v[1:]) != np.signbit(v[:-1])]
    kept: list[float] = []
    for time in crossings:
        if time > 2 * OUTPUT_DT and (not kept or time - kept[-1] > WINDOW):
            kept.append(float(time))
    return np.array(kept)


def _run_around(mask: np.ndarray, centre: int) -> slice | None:
    """The contiguous run of True in ``mask`` nearest to index ``centre`` (None if there is none)."""
    hits = np.flatnonzero(mask)
    if hits.size == 0:
        return None
    start = stop = hits[np.argmin(np.abs(hits - centre))]
    while start > 0 and mask[start - 1]:
        start -= 1
    while stop + 1 < mask.size and mask[stop + 1]:
        stop += 1
    return slice(start, stop + 1)


def reversals(ds: xr.Dataset) -> xr.Dataset:
    """What the thesis shows at each reversal (Figs. 7.16b-d): the nut's stop (start, duration, the screw's travel
    meanwhile), the no-force gap of the contacts, the peak support friction and ball-groove friction torque."""
    t = ds.time.values
    rows = []
    for reversal in reversal_times(ds):
        window = (t >= reversal - WINDOW) & (t <= reversal + WINDOW)
        index = np.flatnonzero(window)
        centre = int(np.searchsorted(t[index], reversal))
        stop = _run_around(np.abs(ds.nut1_speed.values[index]) < STOP_SPEED, centre)
        free = _run_around((np.abs(ds.nut1_contact_force.values[index]) < FORCE_FREE)
                           & (np.abs(ds.nut2_contact_force.values[index]) < FORCE_FREE), centre)
        screw = ds.screw_equivalent_position.values[index]
        rows.append((
            reversal,
            t[index][stop.start] if stop else math.nan,
            (stop.stop - stop.start) * OUTPUT_DT if stop else 0.0,
            abs(screw[stop.stop - 1] - screw[stop.start]) if stop else 0.0,
            (free.stop - free.start) * OUTPUT_DT if free else 0.0,
            float(np.abs(ds.guide_friction.values[index]).max()),
            float(np.abs(ds.ball_groove_friction_torque.values[index]).max()),
        ))
    names = ("reversal_time", "stop_start", "stop_duration", "screw_travel_while_stopped", "force_free_duration",
             "peak_support_friction", "peak_ball_groove_torque")
    units = ("s", "s", "s", "m", "s", "N", "N*m")
    data = np.array(rows).reshape(-1, len(names))
    return xr.Dataset({name: ("reversal", data[:, k], {"units": unit})
                       for k, (name, unit) in enumerate(zip(names, units, strict=True))})


def loop_width(ds: xr.Dataset, start: float = 0.0, end: float = math.inf) -> float:
    """Width of the nut-screw loop of Figs. 7.17c/7.18d [m]: the median nut-minus-screw position while the screw
    drives the master nut one way minus that while it drives it the other (its contact loaded, ``|F_1| >
    FORCE_FREE``, the screw faster than ``MOVING_SPEED``; a nut still crossing its gap or in flight after an
    impact is left out), between ``start`` and ``end``: the gap plus the drive chain's deflection both ways."""
    t = ds.time.values
    relative = (ds.nut1_position - ds.screw_equivalent_position).values
    v = ds.screw_speed.values
    driven = (t >= start) & (t <= end) & (np.abs(ds.nut1_contact_force.values) > FORCE_FREE)
    return float(np.median(relative[driven & (v < -MOVING_SPEED)]) - np.median(relative[driven & (v > MOVING_SPEED)]))


def _contact_constants(params, backlash: float) -> np.ndarray:
    """The model's constants for one nut's contact at ``backlash`` (the plant's own contact functions read them)."""
    scene = load_scene("chapter7_backlash").with_conditions({"backlash": backlash})
    return build_model(scene, params, resolve_fidelity(scene, params, "full")).constants


def hertz_closed_form(params, relative_position: np.ndarray, backlash: float, *, variable_angle: bool = True):
    """Axial contact force of one nut from the thesis's formulas directly [N]: the gap (no force for
    ``|dx| <= b/2``), the angle of Eq. 9.4 (exact form, or the design angle), the series Hertz stiffness of Sec. 7.3
    at that angle (:func:`twin.physics.hertz.ball_groove_stiffness`, unfitted), ``P = K delta^1.5`` (Eq. 7.28) and
    ``F = Z P sin(alpha) cos(alpha_e)`` (Eqs. 9.6, 5.5)."""
    lead, r_m = params.value("ball_screw.lead"), params.value("ball_screw.pitch_radius")
    r_b, f = params.value("ball_screw.ball_radius"), params.value("ball_screw.conformity")
    alpha_0, alpha_e = params.value("ball_screw.contact_angle"), helix_angle(lead, r_m)
    modulus, nu = params.value("ball_screw.elastic_modulus"), params.value("ball_screw.poisson_ratio")
    e_star = hertz.equivalent_modulus(modulus, nu, modulus, nu)
    balls = effective_loaded_balls(params.value("ball_screw.total_balls"),
                                   params.value("ball_screw.loaded_ball_fraction"))
    a0 = groove_centre_distance(r_b, f)
    forces = []
    for dx in np.asarray(relative_position, dtype=float).tolist():
        delta_a = max(abs(dx) - 0.5 * backlash, 0.0) * math.cos(alpha_e)
        if variable_angle:
            delta_n, sin_alpha = contact_geometry(delta_a, a0, a0 * math.cos(alpha_0), a0 * math.sin(alpha_0))
        else:
            sin_alpha = math.sin(alpha_0)
            delta_n = delta_a * sin_alpha
        stiffness = hertz.ball_groove_stiffness(math.asin(sin_alpha), r_m, r_b, 2 * f * r_b, 2 * f * r_b, alpha_e,
                                                params.value("ball_screw.ogival_offset"), e_star)[2]
        forces.append(math.copysign(balls * stiffness * max(delta_n, 0.0) ** 1.5 * sin_alpha * math.cos(alpha_e), dx))
    return np.array(forces)


def preload_curve(params=None, backlash: float = 5.0e-5, peak_displacement: float = 60.0e-6,
                  points: int = 121) -> xr.Dataset:
    """Fig. 7.19: the preload (axial force on the nut, screw fixed) against the nut's displacement from the centre
    of its gap, 0 ... ``peak_displacement``: the twin's contact law (variable and design angle, the run-time
    polynomial stiffness fit) beside :func:`hertz_closed_form`. The triangular preload wave of the thesis is
    quasi-static for this law (rate-independent but for the contact damping), so the curve is the static one."""
    params = params if params is not None else twin.load_parameters("bench")
    c = _contact_constants(params, backlash)
    dx = np.linspace(0.0, peak_displacement, points)
    model = {name: [contact_force(c, code, d) for d in dx.tolist()]
             for name, code in (("variable_angle", CONTACT_VARIABLE_ANGLE), ("design_angle", CONTACT_CONSTANT_ANGLE))}
    return xr.Dataset(
        {"force_variable_angle": ("displacement", np.array(model["variable_angle"]), {"units": "N"}),
         "force_design_angle": ("displacement", np.array(model["design_angle"]), {"units": "N"}),
         "closed_form_variable_angle": ("displacement", hertz_closed_form(params, dx, backlash), {"units": "N"}),
         "closed_form_design_angle": ("displacement", hertz_closed_form(params, dx, backlash, variable_angle=False),
                                      {"units": "N"})},
        coords={"displacement": ("displacement", dx, {"units": "m"})},
        attrs={"backlash": backlash, "loaded_balls": float(c[K.LOADED_BALLS])})


def _loaded(ds: xr.Dataset) -> bool:
    """Whether the run applies an external force (the cylinder's, ``chapter7_backlash_force``)."""
    return json.loads(ds.attrs["scene_conditions"])["cylinder"] == "attached"


def chapter7_study(params=None, runs: dict[str, xr.Dataset] | None = None) -> xr.Dataset:
    """Every Sec. 7.9.3 measurement: per scene its backlash, the reversals (:func:`reversals`, variables and
    dimension prefixed by the scene), the loop width before the external force (and after it, where there is one);
    the Fig. 7.19 curve. ``runs``: the :func:`backlash_run` results to read (run here if not given)."""
    params = params if params is not None else twin.load_parameters("bench")
    runs = runs if runs is not None else {scene: backlash_run(scene, params) for scene in SCENES}
    out = preload_curve(params)
    for scene, ds in runs.items():
        found = reversals(ds)
        out = out.merge(found.rename({name: f"{scene}_{name}" for name in found.data_vars})
                        .rename({"reversal": f"{scene}_reversal"}))
        out[f"{scene}_backlash"] = xr.DataArray(json.loads(ds.attrs["scene_conditions"])["backlash"],
                                                attrs={"units": "m"})
        out[f"{scene}_loop_width"] = xr.DataArray(loop_width(ds, end=FORCE_START), attrs={"units": "m"})
        if _loaded(ds):
            out[f"{scene}_loop_width_loaded"] = xr.DataArray(loop_width(ds, start=FORCE_END + 0.02),
                                                             attrs={"units": "m"})
    return out


def _figure_backlash(scene: str, ds: xr.Dataset, found: xr.Dataset, directory: Path) -> Path:
    """Figs. 7.16a-d/7.17c analogue of one scene: positions, speeds, contact forces, friction, nut minus screw."""
    t = ds.time.values
    fig, axes = plt.subplots(5, 1, figsize=(9, 13), sharex=True)
    axes[0].plot(t, ds.screw_equivalent_position * 1e3, label="screw (equivalent)")
    axes[0].plot(t, ds.nut1_position * 1e3, label="master nut")
    axes[0].plot(t, ds.position_demand * 1e3, "k:", lw=0.8, label="position demand")
    axes[0].set_ylabel("position [mm]")
    axes[1].plot(t, ds.screw_speed * 1e3, label="screw (equivalent)")
    axes[1].plot(t, ds.nut1_speed * 1e3, label="master nut")
    for start, duration in zip(found.stop_start.values, found.stop_duration.values, strict=True):
        if duration > 0:
            axes[1].axvspan(start, start + duration, color="0.85")
    axes[1].set_ylabel("speed [mm/s]")
    axes[2].plot(t, ds.nut1_contact_force, label="master nut")
    axes[2].plot(t, ds.nut2_contact_force, label="slave nut")
    axes[2].set_ylabel("axial contact force [N]")
    axes[3].plot(t, ds.guide_friction, label="support friction, master nut (Eq. 7.63) [N]")
    axes[3].plot(t, ds.ball_groove_friction_torque * 1e3, label="ball-groove friction torque [mN m]")
    axes[3].set_ylabel("friction")
    relative = (ds.nut1_position - ds.screw_equivalent_position) * 1e6
    axes[4].plot(t, relative, label="master nut - screw")
    backlash = json.loads(ds.attrs["scene_conditions"])["backlash"] * 1e6
    for level in (-backlash / 2, backlash / 2):
        axes[4].axhline(level, color="k", ls="--", lw=0.7)
    axes[4].set(ylabel="nut - screw [um]", xlabel="time [s]")
    axes[0].set_title(f"{scene}: Fig. 7.16/7.17 analogue (grey: nut stopped; dashed: +/- b/2)")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    return save_png(fig, directory / f"{scene}.png", FIGURE_DPI)


def _figure_loops(runs: dict[str, xr.Dataset], directory: Path) -> Path:
    """Fig. 7.18d analogue: nut against screw position (as nut minus screw, the loop's width is the gap)."""
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for scene, ds in runs.items():
        early = ds.time.values <= FORCE_START
        ax.plot(ds.screw_equivalent_position.values[early] * 1e3,
                (ds.nut1_position - ds.screw_equivalent_position).values[early] * 1e6, lw=0.8, label=scene)
    ax.set(xlabel="screw equivalent position [mm]", ylabel="master nut - screw [um]",
           title="Fig. 7.18d analogue: backlash loops (t <= 0.25 s)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return save_png(fig, directory / "fig7_18d_loops.png", FIGURE_DPI)


def _figure_preload(curve: xr.Dataset, directory: Path) -> Path:
    """Fig. 7.19 analogue: preload against the nut's displacement from the centre of its gap."""
    fig, ax = plt.subplots(figsize=(6, 4.5))
    dx = curve.displacement.values * 1e6
    ax.plot(dx, curve.force_variable_angle / 1e3, label="twin: Eq. 9.4 variable angle")
    ax.plot(dx, curve.force_design_angle / 1e3, label="twin: design angle")
    ax.plot(dx[::6], curve.closed_form_variable_angle[::6] / 1e3, "k.", label="closed form (unfitted Hertz)")
    ax.axvline(curve.attrs["backlash"] * 5e5, color="0.6", ls="--", label="b/2")
    ax.set(xlabel="nut displacement from the gap's centre [um]", ylabel="preload (axial contact force) [kN]",
           title=f"Fig. 7.19 analogue: b = {curve.attrs['backlash'] * 1e3:g} mm, screw fixed")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return save_png(fig, directory / "fig7_19_preload.png", FIGURE_DPI)


def run_chapter7(directory: str | Path, params=None, scenes=SCENES) -> xr.Dataset:
    """Run the study on ``scenes``, write its figures and ``chapter7.nc`` (the measurements) in ``directory``;
    return the measurements, with the figures' paths in ``attrs["figures"]``."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    params = params if params is not None else twin.load_parameters("bench")
    runs = {scene: backlash_run(scene, params) for scene in scenes}
    out = chapter7_study(params, runs)
    paths = [_figure_backlash(scene, ds, reversals(ds), directory) for scene, ds in runs.items()]
    unloaded = {scene: ds for scene, ds in runs.items() if not _loaded(ds)}
    paths += [_figure_loops(unloaded, directory), _figure_preload(preload_curve(params), directory)]
    out.attrs["figures"] = [str(p) for p in paths]
    out.to_netcdf(directory / "chapter7.nc")
    return out
