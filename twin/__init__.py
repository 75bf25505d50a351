"""BenchTwin: digital twin of the ball-screw test bench of Bertolino (2020), chapter 9.

Pipeline: parameter set + scene -> bench model -> simulation engine -> sensors -> features.

The public names (``twin.simulate``, ``twin.Solver``, ``twin.load_parameters``, ...) are imported on first use
(lazy: start-up cost; ``import twin`` or ``import twin.scenes`` must not load xarray and the compiled
engine). Importing ``sensors`` first keys numba's on-disk cache on the source before any function of
either package is compiled (:mod:`numerics.compiled_cache`; no stale machine code).
"""

import importlib

import sensors  # noqa: F401  (keys the compiled-code cache; see the docstring)

_EXPORTS = {
    "simulate": "twin.simulation",
    "simulate_batch": "twin.simulation",
    "RunSummary": "twin.simulation",
    "Solver": "twin.solver",
    "InputError": "twin.errors",
    "OptionError": "twin.errors",
    "ParameterError": "twin.errors",
    "SceneError": "twin.errors",
    "SimulationFailed": "twin.errors",
    "ParameterSet": "twin.parameters",
    "available_parameter_sets": "twin.parameters",
    "load_parameters": "twin.parameters",
    "Scene": "twin.scenes",
    "list_scenes": "twin.scenes",
    "load_scene": "twin.scenes",
}

__all__ = list(_EXPORTS)


def __getattr__(name: str):
    if name == "__version__":
        return _version()
    if name not in _EXPORTS:
        raise AttributeError(f"module 'twin' has no attribute {name!r}")
    return getattr(importlib.import_module(_EXPORTS[name]), name)


def __dir__() -> list[str]:
    """The module's own names and the lazy ones (``dir(twin)``, tab completion)."""
    return sorted({*globals(), *_EXPORTS, "__version__"})


def _version() -> str:
    """The installed BenchTwin's version (``twin.__version__``, ``twin --version``): the package metadata's, which
    ``pyproject.toml`` sets; ``"unknown (not installed)"`` for a source tree run without installing it."""
    from importlib import metadata

    try:
        return metadata.version("benchtwin")
    except metadata.PackageNotFoundError:
        return "unknown (not installed)"
