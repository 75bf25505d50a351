"""The numerical sensitivity floor of a scene: an ensemble of tight runs that differ only in what should not matter.

A single tight-tolerance run is not a reference where the feature depends on a decision the dynamics make
sensitively: on the thesis data sets without preload, where a free or lightly loaded nut comes to rest inside
its gap, stick or slip of the friction decides where, and any change of the trajectory, however small, can move
the final rest point (docs/accuracy.md, "What the tight reference can and cannot tell"). The ensemble runs the
scene with RK4 at several converged steps that divide the 125 us drive period, and optionally with the scene's
backlash moved by a few picometres (far below anything physical); the spread of its features is the floor below
which no solver comparison on that scene can resolve an error.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

import twin

#: RK4 steps [s] that divide the 125 us drive period and lie on the converged side of the step study
#: (RK4 converges at order ~5 down to 16 us, docs/accuracy.md); 7.8125 us is the historical single reference.
REFERENCE_STEPS = (3.90625e-6, 5.0e-6, 6.25e-6, 7.8125e-6, 12.5e-6, 15.625e-6)
#: Backlash changes [m] of the perturbed members: picometres, far below any tolerance or physical effect.
GAP_PERTURBATIONS = (1e-12, -1e-12, 3e-12, -3e-12)
#: The same where the scene's backlash is 0: upward only (a backlash cannot be negative).
GAP_PERTURBATIONS_AT_ZERO = (1e-12, 2e-12, 3e-12, 4e-12)
FEATURES = ("backlash_feature", "backlash_feature_true")


def reference_ensemble(scene: str | twin.Scene, params: twin.ParameterSet | None = None, *,
                       steps: Sequence[float] = REFERENCE_STEPS, gap_perturbations: Sequence[float] | None = None,
                       perturbed_step: float = 7.8125e-6, features: Sequence[str] = FEATURES,
                       keep_runs: bool = False, **options) -> tuple[xr.Dataset, list[xr.Dataset]]:
    """Run the ensemble of one scene.

    Parameters
    ----------
    scene, params
        As :func:`twin.simulate`.
    steps
        RK4 steps [s], one member each.
    gap_perturbations
        Changes of the scene's ``backlash`` condition [m], one member each, at ``perturbed_step``; None:
        :data:`GAP_PERTURBATIONS` (:data:`GAP_PERTURBATIONS_AT_ZERO` where the backlash is 0).
    features
        Scalar features to collect.
    keep_runs
        Also return every member's full result (for looking at the traces).
    **options
        Passed to :func:`twin.simulate` (``outputs``, ``duration``, ``fidelity``, ``rng``).

    Returns
    -------
    (xarray.Dataset, list of xarray.Dataset)
        The features on a ``member`` dimension (with the member's ``dt`` and ``gap_perturbation``, its ``status``
        and ``wall_time`` (the solver loop alone)), and the members' results if ``keep_runs`` (else an empty list).
    """
    scene = twin.load_scene(scene)
    if gap_perturbations is None:
        gap_perturbations = GAP_PERTURBATIONS if scene.condition("backlash") > 0 else GAP_PERTURBATIONS_AT_ZERO
    members = [(dt, 0.0) for dt in steps] + [(perturbed_step, delta) for delta in gap_perturbations]
    values = np.full((len(members), len(features)), np.nan)
    status, wall, runs = [], [], []
    for k, (dt, delta) in enumerate(members):
        member_scene = scene.with_conditions({"backlash": scene.condition("backlash") + delta}) if delta else scene
        ds = twin.simulate(member_scene, params, solver=twin.Solver("rk4", dt=dt), throw=False, **options)
        status.append(ds.attrs["status"])
        wall.append(float(ds.attrs["wall_time"]))
        if ds.attrs["status"] == "ok":
            values[k] = [float(ds[f]) for f in features]
        if keep_runs:
            runs.append(ds)
    labels = [f"rk4 {dt * 1e6:g} us" + (f", backlash {delta:+.0e} m" if delta else "") for dt, delta in members]
    ensemble = xr.Dataset(
        {f: ("member", values[:, j], {"units": "m"}) for j, f in enumerate(features)}
        | {"status": ("member", status), "wall_time": ("member", wall, {"units": "s"})},
        coords={"member": labels, "dt": ("member", [m[0] for m in members], {"units": "s"}),
                "gap_perturbation": ("member", [m[1] for m in members], {"units": "m"})},
        attrs={"scene": scene.name},
    )
    return ensemble, runs
