"""Work-precision study: error against wall time for every integrator, and the scipy baselines.

Each compiled method runs over a ladder of fixed steps, each adaptive baseline
over a ladder of tolerances; every run is compared with a tight-tolerance
``scipy_radau`` reference of the same scene (:mod:`twin.engine.reference`).
Two panels: instruments ideal ("quantizers off", where each method shows its
convergence order) and the controller's quantisers on (encoders, resolver and
the output converters quantised; analog channels ideal because their sample-and-hold
depends on the stepping grid), where integration errors below a quantisation
decision no longer change the result.
"""

from __future__ import annotations

import os
import platform
import statistics
import time
from datetime import UTC, datetime
from importlib import metadata

import numpy as np
import xarray as xr

import twin
from twin.engine.integrators import INTEGRATORS
from twin.fidelity import full_plant

SPEED_PERIOD = 1.25e-4
STEP_LADDER = tuple(SPEED_PERIOD / 2.0**k for k in range(11))  # 1.25e-4 ... 1.2e-7 s
TOLERANCE_LADDER = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
BASELINES = ("scipy_lsoda", "scipy_radau")
#: The label of the default configuration's point (the step it chooses with the quasi-static screw axial).
DEFAULT_POINT = "default"
REFERENCE = "scipy_radau"
REFERENCE_RTOL = 1e-10
# Full plant; the instruments ideal, or only the digital position sensors and converters quantised.
PANELS = {"quantizers_off": full_plant(),
          "quantizers_on": full_plant(encoders="quantized", output_converters="quantized")}
LONG_RUN = 2.0  # s: runs slower than this are timed once (the median of repeats would cost minutes)
METRICS = {
    "feature_error": ("m", "|backlash_feature - reference| (Eq. 9.12)"),
    "nut_position_error": ("m", "max |nut1_position - reference| over the 1 ms samples"),
    "current_rms_error": ("A", "RMS of motor_current - reference over the 1 ms samples"),
    "pressure_error": ("Pa", "max |chamber pressures - reference| (pneumatics full only)"),
}


def errors(ds: xr.Dataset, reference: xr.Dataset) -> dict[str, float]:
    """The study's error metrics of one run against the reference (NaN when the run failed)."""
    if ds.attrs["status"] != "ok":
        return {name: np.nan for name in METRICS}
    result = {
        "feature_error": abs(float(ds.backlash_feature) - float(reference.backlash_feature)),
        "nut_position_error": float(np.max(np.abs(ds.nut1_position - reference.nut1_position))),
        "current_rms_error": float(np.sqrt(np.mean((ds.motor_current - reference.motor_current) ** 2))),
        "pressure_error": np.nan,
    }
    if "chamber1_pressure" in ds:
        result["pressure_error"] = float(max(np.max(np.abs(ds[p] - reference[p]))
                                             for p in ("chamber1_pressure", "chamber2_pressure")))
    return result


def timed(scene, repeats: int, solver: twin.Solver, fidelity) -> tuple[xr.Dataset, float]:
    """Run once to compile (short), then the median wall time of ``repeats`` runs."""
    twin.simulate(scene, solver=solver, duration=min(scene.duration, 0.01), fidelity=fidelity, throw=False)
    times, ds = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        ds = twin.simulate(scene, solver=solver, fidelity=fidelity, throw=False)
        times.append(time.perf_counter() - start)
        if times[-1] > LONG_RUN:
            break
    return ds, statistics.median(times)


def environment() -> dict[str, str]:
    """Hardware and package versions, recorded with every study."""
    versions = {}
    for package in ("benchtwin", "numpy", "scipy", "numba", "xarray", "control"):
        try:
            versions[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            versions[package] = "not installed"
    return {
        "machine": f"{platform.machine()} {platform.processor()}".strip(),
        "cpu_count": str(os.cpu_count()),
        "python": platform.python_version(),
        "packages": ", ".join(f"{k} {v}" for k, v in versions.items()),
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
    }


def run_study(scene: str | twin.Scene = "nominal", duration: float = 1.5, *, steps=STEP_LADDER,
              methods=tuple(INTEGRATORS), tolerances=TOLERANCE_LADDER, baselines=BASELINES,
              repeats: int = 3, progress=print) -> xr.Dataset:
    """Run the work-precision study and return its data.

    Parameters
    ----------
    scene : str or Scene
        Test procedure (default: the nominal scene, whose first 1.5 s hold the
        sinusoid and the 4 kN force step).
    duration : float
        Simulated time of every run [s].
    steps, methods : sequences
        Fixed steps [s] (each must divide the 125 us speed period) and compiled methods.
    tolerances, baselines : sequences
        ``rtol`` ladder and ``scipy_*`` methods of the adaptive baselines.
    repeats : int
        Timing repeats (median); runs longer than ``LONG_RUN`` are timed once.
    progress : callable
        Receives one line per run.

    Returns
    -------
    xarray.Dataset
        One entry per run along ``run`` with coordinates ``panel``, ``method``,
        ``dt`` (NaN for baselines), ``rtol`` (NaN for fixed steps), and the
        variables ``wall_time`` [s], the :data:`METRICS`, ``status`` and the
        reference's wall time and solver statistics in the attributes.
    """
    scene = twin.load_scene(scene).with_duration(duration)
    records = []
    attrs = {"scene": scene.name, "duration": duration, "reference": f"{REFERENCE} rtol={REFERENCE_RTOL:g}",
             **environment()}
    for panel, fidelity in PANELS.items():
        reference, reference_time = timed(scene, 1, twin.Solver(REFERENCE, rtol=REFERENCE_RTOL), fidelity)
        attrs[f"{panel}_reference_wall_time"] = reference_time
        attrs[f"{panel}_reference_stats"] = ", ".join(f"{k[7:]}={v}" for k, v in reference.attrs.items()
                                                     if k.startswith("solver_"))
        progress(f"[{panel}] reference {REFERENCE}: {reference_time:.2f} s, status {reference.attrs['status']}")
        # the default, which chooses its step with the screw-axial level (the quasi-static shaft, RK4 at the drive
        # period where the current loop is ideal), as one point beside the fixed steps of the full plant
        runs = ([(DEFAULT_POINT, np.nan, np.nan)] + [(m, dt, np.nan) for m in methods for dt in steps]
                + [(b, np.nan, r) for b in baselines for r in tolerances])
        for k, (method, dt, rtol) in enumerate(runs, start=1):
            if method == DEFAULT_POINT:
                ds, wall = timed(scene, repeats, twin.Solver("rk4"), {**fidelity, "screw_axial": "quasi_static"})
            else:
                solver = twin.Solver(method, dt=dt) if np.isfinite(dt) else twin.Solver(method, rtol=rtol)
                ds, wall = timed(scene, repeats, solver, fidelity)
            metrics = errors(ds, reference)
            if method == DEFAULT_POINT:
                method, dt = f"{DEFAULT_POINT} (rk4, quasi-static screw axial)", ds.attrs["dt"]
            records.append({"panel": panel, "method": method, "dt": dt, "rtol": rtol, "wall_time": wall,
                            "status": ds.attrs["status"], **metrics})
            # every entry a number or the reason it is none: adaptive methods have no fixed step, fixed steps no rtol
            setting = f"dt={dt:9.3g} s (fixed step)    " if np.isfinite(dt) else f"rtol={rtol:7.1g} (adaptive step)"
            outcome = (f"feature error={metrics['feature_error']:.3g} m" if ds.attrs["status"] == "ok" else
                       f"status={ds.attrs['status']}: no error (the step is beyond this method's stability limit, "
                       "see the stability map)" if ds.attrs["status"] == "diverged" else
                       f"status={ds.attrs['status']}: no error ({ds.attrs.get('failure_reason', '')})")
            progress(f"[{panel} {k}/{len(runs)}] {method:20s} {setting} wall={wall:8.4f} s {outcome}")
    return _to_dataset(records, attrs)


def _to_dataset(records: list[dict], attrs: dict) -> xr.Dataset:
    run = np.arange(len(records))
    data = {
        "wall_time": ("run", [r["wall_time"] for r in records],
                      {"units": "s", "long_name": "median wall time of one run"}),
        "status": ("run", np.array([r["status"] for r in records], dtype=str), {"long_name": "run status"}),
    }
    for name, (units, long_name) in METRICS.items():
        data[name] = ("run", [r[name] for r in records], {"units": units, "long_name": long_name})
    coords = {
        "run": run,
        "panel": ("run", np.array([r["panel"] for r in records], dtype=str)),
        "method": ("run", np.array([r["method"] for r in records], dtype=str)),
        "dt": ("run", [r["dt"] for r in records], {"units": "s", "long_name": "fixed step (NaN: adaptive)"}),
        "rtol": ("run", [r["rtol"] for r in records],
                 {"units": "1", "long_name": "relative tolerance (NaN: fixed step)"}),
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


def quantization_floor(study: xr.Dataset, metric: str = "feature_error") -> float:
    """Error level below which the quantised panel stops improving.

    With the quantisers on, an integration error only matters when it flips a
    quantisation decision (an encoder count, a resolver step, a converter code);
    once it is below that, every method lands on the same sequence of decisions
    and the error is the reference's own decision noise. Estimated as the median
    error of the successful fixed-step runs at the three finest steps.
    """
    on = study.where((study.panel == "quantizers_on") & np.isfinite(study.dt) & (study.status == "ok"), drop=True)
    finest = np.sort(np.unique(on.dt.values))[:3]
    values = on[metric].where(on.dt.isin(finest), drop=True).values
    values = values[np.isfinite(values)]
    return float(np.median(values)) if values.size else float("nan")
