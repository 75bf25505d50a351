"""Where explicit methods fail: the largest stable step against contact stiffness and sled mass.

For each condition the bench is loaded statically (preload, external force from an ideal
source, the sled held by the loops) and run closed loop with each explicit method; the largest
step whose run stays ``ok`` (no NaN, no physical bound, no persistent local-error excess: the
engine's divergence guard) is found by bisection over the steps ``1 ms / n``. So that any such
step keeps the controllers' sample instants on step boundaries, the probe samples the drive's
speed loop at every step (the stiff plant modes, not the slow loops, set the limit).
The theoretical limits are ``2.8 / omega`` for RK4 (the reach of its stability region on the
imaginary axis; 2.785 on the real axis) and ``2 / omega`` for the semi-implicit Euler (explicit
Euler on the first-order states, symplectic Euler on the oscillators), with ``omega`` the largest
eigenvalue modulus of the Jacobian at the loaded state (:mod:`twin.engine.linearize`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

import twin
from twin.engine.linearize import highest_frequency, jacobian
from twin.engine.model import build_model
from twin.fidelity import full_plant, resolve_fidelity
from twin.layout import N_INPUTS, U
from twin.scenes import scene_from_dict

# The full plant (every stiff mode present) with an ideal force source and ideal instruments.
STUDY_FIDELITY = full_plant("ideal")

THEORY = {"rk4": 2.8, "semi_implicit_euler": 2.0}
PRELOADS = (0.0, 1000.0, 3000.0)
FORCES = (0.0, 4000.0, 8000.0)
MASSES = (2.0, 4.0, 8.0, 16.0)
FINE_STEP = 1.5625e-5
POSITION_PERIOD = 1e-3  # s, the controller's sample period: every probe step divides it


def loaded_scene(preload: float, force: float, duration: float = 0.25) -> twin.Scene:
    """Sled held still; the external force rises in 50 ms from 20 ms (ideal source)."""
    return scene_from_dict({
        "name": f"hold_pr{preload:g}_f{force:g}", "duration": duration,
        "force_demand": [{"kind": "hold", "end": 0.02}, {"kind": "smooth_step", "end": 0.07, "to": force}],
        "conditions": {"preload": preload, "preload_configuration": "O", "backlash": 0.0,
                       "room_temperature": 298.15, "supply_pressure": 7.0e5},
    })


def loaded_state(scene, params):
    """Model, state and held inputs at the end of a fine RK4 run of ``scene``."""
    ds = twin.simulate(scene, params, solver=twin.Solver("rk4", dt=FINE_STEP), fidelity=STUDY_FIDELITY)
    model = build_model(scene, params, resolve_fidelity(scene, params, STUDY_FIDELITY))
    inputs = np.zeros(N_INPUTS)
    inputs[U.CURRENT_DEMAND] = float(ds.current_demand[-1])
    return model, ds.final_state.values.copy(), inputs


def runs_ok(scene, params, method: str, n: int) -> bool:
    """Whether the closed-loop run at ``dt = 1 ms / n`` (speed loop sampled every step) ends ``ok``."""
    dt = POSITION_PERIOD / n
    probe = params.with_values({"drive.speed_loop_sample_time": dt})
    ds = twin.simulate(scene, probe, solver=twin.Solver(method, dt=dt), fidelity=STUDY_FIDELITY, throw=False)
    return ds.attrs["status"] == "ok"


def largest_stable_step(scene, params, method: str, n_low: int = 4, n_high: int = 400) -> float:
    """Bisection over ``n`` for the largest stable step ``1 ms / n`` of ``method`` [s] (NaN if none)."""
    if runs_ok(scene, params, method, n_low):
        return POSITION_PERIOD / n_low
    if not runs_ok(scene, params, method, n_high):
        return float("nan")
    while n_high - n_low > 1:
        middle = (n_low + n_high) // 2
        if runs_ok(scene, params, method, middle):
            n_high = middle
        else:
            n_low = middle
    return POSITION_PERIOD / n_high


def stability_map(methods=tuple(THEORY), preloads=PRELOADS, forces=FORCES, masses=MASSES,
                  progress=print) -> xr.Dataset:
    """Measured and theoretical step limits over a stiffness sweep (preload x force) and a mass sweep.

    Returns
    -------
    xarray.Dataset
        Along ``case``: ``preload`` [N], ``force`` [N], ``master_mass`` [kg], ``omega_max``
        [rad/s]; per method ``limit_<method>`` (measured) and ``theory_<method>`` [s].
    """
    bench = twin.load_parameters()
    cases = [(p, f, bench.value("sled.master_mass")) for p in preloads for f in forces]
    cases += [(1000.0, 4000.0, m) for m in masses]
    records = []
    for preload, force, mass in cases:
        params = bench.with_values({"sled.master_mass": mass})
        scene = loaded_scene(preload, force)
        model, x0, inputs = loaded_state(scene, params)
        omega = highest_frequency(jacobian(model, x0, t=scene.duration, u=inputs))
        record = {"preload": preload, "force": force, "master_mass": mass, "omega_max": omega}
        for method in methods:
            record[f"limit_{method}"] = largest_stable_step(scene, params, method)
            record[f"theory_{method}"] = THEORY[method] / omega
        records.append(record)
        progress(", ".join(f"{k}={v:.4g}" for k, v in record.items()))
    data = {k: ("case", [r[k] for r in records]) for k in records[0] if k not in ("preload", "force", "master_mass")}
    coords = {k: ("case", [r[k] for r in records]) for k in ("preload", "force", "master_mass")}
    ds = xr.Dataset(data, coords={"case": np.arange(len(records)), **coords})
    ds["omega_max"].attrs.update(units="rad/s", long_name="largest Jacobian eigenvalue modulus at the loaded state")
    for method in methods:
        ds[f"limit_{method}"].attrs.update(units="s", long_name=f"largest stable step of {method} (measured)")
        ds[f"theory_{method}"].attrs.update(units="s", long_name=f"{THEORY[method]} / omega_max")
    return ds
