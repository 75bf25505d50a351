"""BenchTwin: digital twin of the ball-screw test bench of Bertolino (2020), chapter 9.

Pipeline: parameter set + scene -> bench model -> simulation engine -> sensors -> features.
"""

# First, before any numba function is decorated: importing sensors keys the compiled-code cache on the
# source (sensors.compiled_cache; no stale machine code).
import sensors  # noqa: F401

from twin.simulation import simulate  # noqa: E402
from twin.errors import InputError, OptionError, ParameterError, SceneError, SimulationFailed  # noqa: E402
from twin.parameters import ParameterSet, available_parameter_sets, load_parameters  # noqa: E402
from twin.scenes import Scene, list_scenes, load_scene  # noqa: E402

__all__ = [
    "simulate", "load_parameters", "load_scene", "list_scenes", "available_parameter_sets",
    "Scene", "ParameterSet", "InputError", "OptionError", "ParameterError", "SceneError", "SimulationFailed",
]
