"""Helpers shared by the bench tests (importable: conftest modules are not)."""

import twin
from twin.fidelity import IDEAL_INSTRUMENTS


def plant_fidelity(scene) -> dict:
    """The full plant seen through ideal instruments, with the load system only where the scene
    demands a force: the setting of the physics and solver tests (every stiff mode present)."""
    scene = twin.load_scene(scene)
    return {"default": "full", **IDEAL_INSTRUMENTS, "pneumatics": "full" if scene.has_force_demand else "absent"}
