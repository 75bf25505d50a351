"""The bench twin as a campaign model: its catalog and the default run function.

This is the only module of the package that calls ``twin``; it imports it lazily,
so the campaign machinery (and its tests with the synthetic model) does not pay
for numba compilation where no bench run happens.
"""

from __future__ import annotations

import math
from functools import lru_cache

from campaigns.catalog import CONDITION_CHOICES, CONDITION_UNITS, lookup_nominal
from campaigns.runs import RunRequest
from twin.engine.features import FEATURES
from twin.errors import InputError

#: Features the bench computes (``twin.simulate`` scalar outputs), with unit and long name: the
#: declarations of :mod:`twin.engine.features` (a light module: no numba compilation on import).
BENCH_FEATURES: dict[str, tuple[str, str]] = {name: (f.unit, f.long_name) for name, f in FEATURES.items()}


def scene_conditions(scene) -> dict[str, float]:
    """Numeric conditions of a scene (``scene.conditions``) that campaigns know units for."""
    return {k: float(v) for k, v in scene.conditions.items() if k in CONDITION_UNITS}


class BenchCatalog:
    """Catalog of the bench twin for one parameter set and base scene.

    Parameters
    ----------
    parameters : str
        Parameter-set name or path (``twin.load_parameters``).
    scene : str
        Base scene name or path (``twin.load_scene``); its conditions are the
        nominal values of ``scene.*`` targets.

    Raises
    ------
    twin.errors.InputError
        If the twin, the parameter set or the scene cannot be loaded.
    """

    feature_units = BENCH_FEATURES

    def __init__(self, parameters: str = "bench", scene: str = "nominal"):
        try:
            import twin

            params = twin.load_parameters(parameters)
            base_scene = twin.load_scene(scene)
            self.scene_names = list(twin.list_scenes())
            from twin.scenes import CONDITIONS

            self.condition_names = [c for c in CONDITIONS if c in CONDITION_UNITS or c in CONDITION_CHOICES]
        except InputError:
            raise
        except Exception as exc:  # twin missing or broken: report it as a spec problem
            raise InputError("bench twin", [f"cannot load parameters {parameters!r} / scene {scene!r}: {type(exc).__name__}: {exc}"]) from exc
        self._parameters = {n: (params[n].value, params[n].unit) for n in params.names}
        self._conditions = scene_conditions(base_scene)

    @property
    def parameter_names(self) -> list[str]:
        return list(self._parameters)

    def nominal(self, target: str) -> tuple[float, str]:
        return lookup_nominal(target, self._parameters, self._conditions)


@lru_cache(maxsize=8)
def _scene(name: str):
    import twin

    return twin.load_scene(name)


@lru_cache(maxsize=2)
def _parameters(name: str):
    import twin

    return twin.load_parameters(name)


def simulate_run(request: RunRequest) -> dict:
    """Default run function: one ``twin.simulate`` call (see :mod:`campaigns.runs` for the contract).

    The run's noise generator goes to ``twin.simulate``; the compiled loop cannot
    be interrupted from inside, so the per-run timeout is the sandbox's kill
    (:mod:`campaigns.sandbox`).
    """
    import twin

    scene = _scene(request.scene).with_conditions(request.conditions)
    params = _parameters(request.parameters).with_values(request.parameter_values)
    options = {k: v for k, v in request.solver.items() if v is not None}
    ds = twin.simulate(scene, params, throw=False, rng=request.noise_rng(), outputs=list(request.outputs) or None,
                       **options)
    trace = None
    if request.trace_variables:
        kept = [v for v in request.trace_variables if v in ds]
        trace = ds[kept].isel(time=slice(None, None, request.trace_decimation))
    return {
        "status": ds.attrs.get("status", "ok"),
        "failure_reason": ds.attrs.get("failure_reason", ""),
        "t_reached": float(ds.attrs.get("t_reached", math.nan)),
        "features": {f: float(ds[f]) for f in request.features if f in ds},
        "trace": trace,
        "fidelity": ds.attrs.get("fidelity", ""),
    }
