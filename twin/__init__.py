"""BenchTwin: digital twin of the ball-screw test bench of Bertolino (2020), chapter 9.

Pipeline: parameter set + scene -> bench model -> simulation engine -> sensors -> features.
"""

from twin.engine.simulate import simulate
from twin.errors import InputError, OptionError, ParameterError, SceneError, SimulationFailed
from twin.parameters import ParameterSet, available_parameter_sets, load_parameters
from twin.scenes import Scene, list_scenes, load_scene

__all__ = [
    "simulate", "load_parameters", "load_scene", "list_scenes", "available_parameter_sets",
    "Scene", "ParameterSet", "InputError", "OptionError", "ParameterError", "SceneError", "SimulationFailed",
]
