"""Validation of the reduced ball screw against the thesis's Ch. 5 results (Figs. 5.6-5.13) and the drag torque
of Eq. 7.85 (Fig. 7.22): the figures regenerated with BenchTwin's model, and the numbers docs/validation.md quotes.

Steady efficiency (Figs. 5.6-5.10) is Eq. 5.25 at constant screw speed, from the plant's own functions
(:func:`twin.engine.plant.ball_screw_outputs`): the nuts follow the screw, each carries its axial load through
its contact (the per-sphere normal load and contact angle of Eqs. 9.4-9.6), and the friction of Eqs. 5.16-5.24
acts at those loads. Two load-sharing conventions are drawn:

* ``chapter5``: the Ch. 5 assumption (Sec. 5.2, Eq. 5.6): the external force split equally between the nuts and
  a constant preload force, nut loads ``F_pr + F/2`` and ``-F_pr + F/2``; the second nut changes side at
  ``F = 2 F_pr`` (Fig. 5.13d, the "transition point" of Fig. 5.7);
* ``bench``: the bench of Ch. 9 (Eq. 9.8): the force on the master nut, the preload from a soft disc-spring set
  that keeps the slave's load: ``F_pr + F`` and ``-F_pr`` (the spring's small change with the master's
  deflection, tests/engine/test_ball_screw_chapter5.py, is left out of these curves).

The hysteresis of Figs. 5.11-5.12 is simulated: the full closed-loop twin with a sinusoidal position demand, no
preload, no external force (cylinder detached), and three backlashes.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (backend must be chosen first)
import numpy as np  # noqa: E402

import twin  # noqa: E402
from app.studies.charts import save_png  # noqa: E402
from twin.engine.codes import CONTACT  # noqa: E402
from twin.engine.model import build_model, contact_position_for_force  # noqa: E402
from twin.engine.plant import ball_screw_outputs, internal_forces, work_rows  # noqa: E402
from twin.fidelity import resolve_fidelity  # noqa: E402
from twin.layout import K, S  # noqa: E402
from twin.physics.ball_groove_friction import catalogue_drag_torque  # noqa: E402
from twin.physics.ball_screw import helix_angle  # noqa: E402
from twin.scenes import scene_from_dict  # noqa: E402

FIGURE_DPI = 110  # the resolution of the study's PNG figures

RPM = 2.0 * math.pi / 60.0
SPEEDS_RPM = (100.0, 500.0, 1500.0)  # screw speeds of the efficiency curves (the bench's motor tops 7000/4 rpm)
DYNAMIC_LOAD = 8200.0  # N, C_a of Table 7.5: the Ch. 5 study sweeps the external force over 0 - C_a
NOMINAL_FORCE = 0.5 * DYNAMIC_LOAD  # Sec. 5.3: F_ext,nom = C_a / 2
NOMINAL_PRELOAD = NOMINAL_FORCE / 2.0**1.5  # Eq. 5.26 (ISO 3408-4)
SHARINGS = ("chapter5", "bench")


#: Conditions of the study's scenes besides preload and backlash: the nominal scene's room and supply, O preload,
#: no cylinder (Ch. 5 has no load system: "inputs are the torque on the screw shaft, the preload and the
#: external force", Fig. 5.5).
CONDITIONS = {"preload_configuration": "O", "room_temperature": 293.15, "supply_pressure": 7.0e5,
              "cylinder": "detached", "zero_procedure": "preloaded"}


def _scene(preload: float, backlash: float = 0.0):
    return scene_from_dict({"name": "chapter5", "duration": 1.0, "position_demand": [], "force_demand": [],
                            "conditions": {**CONDITIONS, "preload": preload, "backlash": backlash}})


def _model(params, preload: float = 0.0):
    scene = _scene(preload)
    return build_model(scene, params, resolve_fidelity(scene, params, {"default": "full", "nut_rotation": "off"}))


def nut_loads(preload: float, load: float, sharing: str) -> tuple[float, float]:
    """Axial contact forces of the master and slave nut [N] for a load ``load`` opposing the motion."""
    if sharing == "chapter5":
        return preload + 0.5 * load, -preload + 0.5 * load
    return preload + load, -preload


def steady_efficiency(params, preload: float, load: float, screw_speed: float, sharing: str = "chapter5",
                      model=None) -> tuple[float, float]:
    """Eq. 5.25 efficiency and ball-groove friction torque [N m] at constant screw speed [rad/s] (module docstring)."""
    model = model if model is not None else _model(params)
    c, contact_model = model.constants, int(model.levels[CONTACT])
    x = model.initial_state.copy()
    f1, f2 = nut_loads(preload, load, sharing)
    x[S.NUT1_POSITION] = -contact_position_for_force(c, contact_model, f1)
    x[S.NUT2_POSITION] = -contact_position_for_force(c, contact_model, f2)
    x[S.SCREW_SPEED] = screw_speed
    x[S.NUT1_SPEED] = x[S.NUT2_SPEED] = c[K.LEAD_ARM] * screw_speed
    # one run as a one-lane group of the engine ([row, lane] arrays): the forces, then the outputs from them
    lane_x, lane_c, w = x.reshape(-1, 1), c.reshape(-1, 1), work_rows(1)
    internal_forces(0.0, lane_x, lane_c, w, 1, model.levels, model.force_table)
    torque, efficiency, _, _ = ball_screw_outputs(lane_x, lane_c, w, 0)
    return efficiency, torque


def efficiency_study(params) -> dict:
    """The data of Figs. 5.6-5.10 (our model) as nested lists, with their axes."""
    base = _model(params)
    loads = np.linspace(0.0, DYNAMIC_LOAD, 83)
    preloads = np.linspace(0.0, 2.0 * NOMINAL_PRELOAD, 59)
    out = {"loads": loads.tolist(), "preloads": preloads.tolist(), "speeds_rpm": list(SPEEDS_RPM),
           "nominal_force": NOMINAL_FORCE, "nominal_preload": NOMINAL_PRELOAD}
    for sharing in SHARINGS:
        out[f"vs_force_{sharing}"] = {
            f"{pr:.0f}|{rpm:.0f}": [steady_efficiency(params, pr, f, rpm * RPM, sharing, base)[0] for f in loads]
            for pr in (0.5 * NOMINAL_PRELOAD, NOMINAL_PRELOAD, 2.0 * NOMINAL_PRELOAD) for rpm in SPEEDS_RPM}
        out[f"vs_preload_{sharing}"] = {
            f"{f:.0f}|{rpm:.0f}": [steady_efficiency(params, pr, f, rpm * RPM, sharing, base)[0] for pr in preloads]
            for f in (0.5 * NOMINAL_FORCE, NOMINAL_FORCE, 2.0 * NOMINAL_FORCE) for rpm in SPEEDS_RPM}
    k_rf = np.linspace(0.5, 2.0, 7)
    out["k_rf"] = k_rf.tolist()
    scaled = [params.with_values({"ball_screw.rolling_friction_multiplier": k}) for k in k_rf]
    out["vs_k_rf"] = {f"{rpm:.0f}": [steady_efficiency(q, NOMINAL_PRELOAD, NOMINAL_FORCE, rpm * RPM)[0] for q in scaled]
                      for rpm in SPEEDS_RPM}
    map_loads, map_preloads = np.linspace(200.0, DYNAMIC_LOAD, 40), np.linspace(0.0, 2.0 * NOMINAL_PRELOAD, 30)
    out["map"] = {"loads": map_loads.tolist(), "preloads": map_preloads.tolist(),
                  "efficiency": [[steady_efficiency(params, pr, f, 0.4 * 1500.0 * RPM, "chapter5", base)[0]
                                  for f in map_loads] for pr in map_preloads]}
    return out


def drag_study(params) -> dict:
    """No-load drag torque against the preload (Fig. 7.22 analogue) beside Eq. 7.85, at 100 and 500 rpm."""
    preloads = np.linspace(0.0, 3500.0, 36)
    lead, radius = params.value("ball_screw.lead"), params.value("ball_screw.pitch_radius")
    out = {"preloads": preloads.tolist(),
           "catalogue": [catalogue_drag_torque(lead, f, helix_angle(lead, radius)) for f in preloads]}
    for rpm in (100.0, 500.0):
        out[f"model_{rpm:.0f}"] = [steady_efficiency(params, f, 0.0, rpm * RPM, "chapter5")[1] for f in preloads]
    return out


def hysteresis_study(params, backlashes=(0.0, 10e-6, 40e-6), duration: float = 4.0) -> dict:
    """Figs. 5.11-5.12: sinusoidal position demand (10 mm, 0.5 Hz), no preload, no force, cylinder detached."""
    out = {}
    for b in backlashes:
        scene = scene_from_dict({
            "name": f"hysteresis_{b * 1e6:.0f}um", "duration": duration,
            "position_demand": [{"kind": "hold", "end": 0.2},
                                {"kind": "sinusoid", "end": duration, "amplitude": 0.01, "frequency": 0.5,
                                 "phase": 0.0}],
            "force_demand": [],
            "conditions": {**CONDITIONS, "preload": 0.0, "backlash": b}})
        ds = twin.simulate(scene, params, rng=0, fidelity={"encoders": "ideal", "analog_sensors": "ideal"})
        keep = slice(None, None, 10)
        out[f"{b * 1e6:.0f}"] = {
            "time": ds.time.values[keep].tolist(),
            "screw": ds.screw_equivalent_position.values[keep].tolist(),
            "nut": ds.nut1_position.values[keep].tolist(),
            "nut_speed": ds.nut1_speed.values[keep].tolist(),
            "demand": ds.position_demand.values[keep].tolist(),
            "hysteresis_true": float(ds.backlash_hysteresis_true),
            "friction_torque_max": float(np.abs(ds.ball_groove_friction_torque).max()),
        }
    return out


def regimes_study(params, preload: float = 1000.0) -> dict:
    """Fig. 5.13: contact force of each nut against the external force, both load-sharing conventions."""
    forces = np.linspace(-3.0 * preload, 3.0 * preload, 121)
    out = {"forces": forces.tolist(), "preload": preload}
    for sharing in SHARINGS:
        loads = [nut_loads(preload, f, sharing) for f in forces]
        out[sharing] = {"nut1": [a for a, _ in loads], "nut2": [b for _, b in loads]}
    # where a nut's contact changes side: the load F here opposes a +x motion, i.e. the external force on the
    # nuts is -F; on the bench the master changes side when the external force (+x) exceeds the preload
    out["transition"] = {"chapter5": [-2.0 * preload, 2.0 * preload], "bench": [-preload],
                         "rigid_spacer": [-(2.0**1.5) * preload, 2.0**1.5 * preload]}
    return out


def _efficiency_pair(data: dict, x: np.ndarray, sweep: str, curve_label, xlabel: str, figure: str,
                     transitions: bool = False):
    """Figs. 5.6/5.7 analogues: efficiency along one sweep, a panel per load sharing; each curve is keyed
    ``"<level>|<rpm>"`` (the other load's level) and labelled by ``curve_label(level, rpm)``; with
    ``transitions`` the Ch. 5 panel marks each curve's transition point ``F_pr = level / 2``."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, sharing in zip(axes, SHARINGS, strict=True):
        for key, values in data[f"vs_{sweep}_{sharing}"].items():
            level, rpm = key.split("|")
            ax.plot(x, values, label=curve_label(float(level), rpm))
            if transitions and sharing == "chapter5":
                ax.axvline(float(level) / 2e3, color="0.7", lw=0.6, ls=":")
        ax.set(xlabel=xlabel, title=f"Fig. {figure} analogue, load sharing: {sharing}")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("direct efficiency (Eq. 5.25)")
    axes[1].legend(fontsize=7)
    return fig, axes


def _figure_efficiency(data: dict, directory: Path) -> list[Path]:
    paths = []
    fig, _ = _efficiency_pair(data, np.array(data["loads"]) / 1e3, "force",
                              lambda preload, rpm: f"F_pr {preload / 1e3:.2g} kN, {rpm} rpm", "external force [kN]",
                              "5.6")
    paths.append(save_png(fig, directory / "fig5_6_efficiency_vs_force.png", FIGURE_DPI))

    fig, axes = _efficiency_pair(data, np.array(data["preloads"]) / 1e3, "preload",
                                 lambda force, rpm: f"F_ext {force / 1e3:.3g} kN, {rpm} rpm", "preload [kN]", "5.7",
                                 transitions=True)
    axes[0].text(0.02, 0.03, "dotted: transition points F_pr = F_ext/2", transform=axes[0].transAxes, fontsize=7)
    paths.append(save_png(fig, directory / "fig5_7_efficiency_vs_preload.png", FIGURE_DPI))

    fig, ax = plt.subplots(figsize=(5.5, 4))
    for rpm, values in data["vs_k_rf"].items():
        ax.plot(data["k_rf"], values, "o-", label=f"{rpm} rpm")
    ax.set(xlabel="k_rf (rolling friction multiplier)", ylabel="direct efficiency (Eq. 5.25)",
           title="Fig. 5.8 analogue: nominal F_ext, F_pr")
    ax.grid(alpha=0.3)
    ax.legend()
    paths.append(save_png(fig, directory / "fig5_8_efficiency_vs_krf.png", FIGURE_DPI))

    m = data["map"]
    fig, ax = plt.subplots(figsize=(6, 4.5))
    contour = ax.contourf(np.array(m["loads"]) / 1e3, np.array(m["preloads"]) / 1e3, np.array(m["efficiency"]),
                          np.linspace(0.6, 0.93, 23), extend="min")
    fig.colorbar(contour, label="direct efficiency (Eq. 5.25)")
    ax.plot(np.array(m["loads"]) / 1e3, np.array(m["loads"]) / 1e3 / 2.0**1.5, "r-", label="ISO 3408-4: F_pr = F/2^1.5")
    ax.plot(np.array(m["loads"]) / 1e3, np.array(m["loads"]) / 2e3, "w--", label="transition F_pr = F/2")
    ax.set(xlabel="external force [kN]", ylabel="preload [kN]", title="Fig. 5.10 analogue (Ch. 5 sharing, 600 rpm)",
           ylim=(0, max(m["preloads"]) / 1e3))
    ax.legend(fontsize=7, loc="upper left")
    paths.append(save_png(fig, directory / "fig5_10_efficiency_map.png", FIGURE_DPI))
    return paths


def _figure_drag(data: dict, directory: Path) -> Path:
    fig, ax = plt.subplots(figsize=(5.5, 4))
    preloads = np.array(data["preloads"])
    ax.plot(preloads, data["catalogue"], "k--", label="Eq. 7.85 (catalogue)")
    for key in ("model_100", "model_500"):
        ax.plot(preloads, data[key], label=f"model, {key.split('_')[1]} rpm")
    ax.set(xlabel="preload [N]", ylabel="no-load drag torque [N m]", title="Fig. 7.22 analogue (20 degC)")
    ax.grid(alpha=0.3)
    ax.legend()
    return save_png(fig, directory / "fig7_22_drag_torque.png", FIGURE_DPI)


def _figure_hysteresis(data: dict, directory: Path) -> list[Path]:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    zoom = (0.6, 0.9)  # s: the first reversal of the sinusoid (at 0.7 s)
    for b, run in data.items():
        t = np.array(run["time"])
        axes[0].plot(t, (np.array(run["nut"]) - np.array(run["screw"])) * 1e6, label=f"b = {b} um")
        near = (t >= zoom[0]) & (t <= zoom[1])
        axes[1].plot(t[near], np.array(run["nut_speed"])[near] * 1e3, label=f"nut, b = {b} um")
    first = next(iter(data.values()))
    t = np.array(first["time"])
    near = (t >= zoom[0]) & (t <= zoom[1])
    screw_speed = np.gradient(np.array(first["screw"]), t)
    axes[1].plot(t[near], screw_speed[near] * 1e3, "k:", lw=1.0, label="screw (b = 0)")
    axes[0].set(xlabel="time [s]", ylabel="nut - screw equivalent position [um]",
                title="Fig. 5.11 analogue: the nut leaves the screw by the backlash")
    axes[1].set(xlabel="time [s]", ylabel="speed [mm/s]", title="speeds at the first reversal")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    paths = [save_png(fig, directory / "fig5_11_positions.png", FIGURE_DPI)]
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    for b, run in data.items():
        screw = np.array(run["screw"]) * 1e3
        ax.plot(screw, (np.array(run["nut"]) - np.array(run["screw"])) * 1e6,
                label=f"b = {b} um: H = {run['hysteresis_true'] * 1e6:.1f} um")
    ax.set(xlabel="screw equivalent position [mm]", ylabel="nut - screw [um]",
           title="Fig. 5.12 analogue: backlash hysteresis")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    paths.append(save_png(fig, directory / "fig5_12_hysteresis.png", FIGURE_DPI))
    return paths


def _figure_regimes(data: dict, directory: Path) -> Path:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    forces = np.array(data["forces"]) / 1e3
    for ax, sharing in zip(axes, SHARINGS, strict=True):
        ax.plot(forces, np.array(data[sharing]["nut1"]) / 1e3, label="nut 1 (master)")
        ax.plot(forces, np.array(data[sharing]["nut2"]) / 1e3, label="nut 2 (slave)")
        ax.axhline(0.0, color="k", lw=0.6)
        for k, load in enumerate(data["transition"][sharing]):
            ax.axvline(load / 1e3, color="r", ls="--",
                       label=f"side change at {abs(load) / data['preload']:g} F_pr" if k == 0 else None)
        ax.set(xlabel="load F opposing a +x motion (external force -F) [kN]", title=f"Fig. 5.13 regimes, {sharing}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylabel("axial contact force of the screw on the nut [kN]")
    return save_png(fig, directory / "fig5_13_regimes.png", FIGURE_DPI)


def run_chapter5(directory: str | Path, params=None, *, dynamic: bool = True) -> dict:
    """Compute every study, write the figures and ``chapter5.json`` in ``directory``; return the key numbers."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    params = params if params is not None else twin.load_parameters("bench")
    efficiency, drag, regimes = efficiency_study(params), drag_study(params), regimes_study(params)
    paths = _figure_efficiency(efficiency, directory) + [_figure_drag(drag, directory),
                                                         _figure_regimes(regimes, directory)]
    data = {"efficiency": efficiency, "drag": drag, "regimes": regimes}
    if dynamic:
        hysteresis = hysteresis_study(params)
        paths += _figure_hysteresis(hysteresis, directory)
        data["hysteresis"] = hysteresis
    (directory / "chapter5.json").write_text(json.dumps(data))
    return {"figures": [str(p) for p in paths], "summary": summary(data)}


def summary(data: dict) -> dict:
    """The numbers docs/validation.md quotes."""
    e = data["efficiency"]
    loads = np.array(e["loads"])
    nominal = e["vs_force_chapter5"][f"{e['nominal_preload']:.0f}|500"]
    peak = int(np.nanargmax(nominal))
    drag = data["drag"]
    ratio = np.array(drag["model_100"][1:]) / np.array(drag["catalogue"][1:])
    out = {
        "efficiency_at_zero_load": nominal[0],
        "peak_efficiency": nominal[peak], "peak_at_force": float(loads[peak]),
        "peak_over_preload": float(loads[peak] / e["nominal_preload"]),
        "efficiency_at_C_a": nominal[-1],
        "efficiency_vs_krf": e["vs_k_rf"]["500"],
        "drag_ratio_to_catalogue_range": [float(ratio.min()), float(ratio.max())],
        "drag_at_1kN_100rpm": float(np.interp(1000.0, drag["preloads"], drag["model_100"])),
    }
    if "hysteresis" in data:
        out["hysteresis_true_um"] = {b: run["hysteresis_true"] * 1e6 for b, run in data["hysteresis"].items()}
    return out
