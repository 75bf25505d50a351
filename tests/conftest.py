"""Shared fixtures: the bench parameter set and small scenes built in code."""

import pytest

import twin
from twin.scenes import scene_from_dict

ROOM = 298.15


@pytest.fixture(scope="session")
def bench():
    return twin.load_parameters("bench")


def make_scene(duration, position=(), force=(), *, preload=0.0, backlash=0.0, configuration="O", name="test"):
    """A scene from demand segments (lists of dicts) and conditions."""
    return scene_from_dict({
        "name": name,
        "duration": duration,
        "position_demand": list(position),
        "force_demand": list(force),
        "conditions": {"preload": preload, "preload_configuration": configuration, "backlash": backlash,
                       "room_temperature": ROOM, "supply_pressure": 7.0e5},
    })


@pytest.fixture(scope="session")
def scene_factory():
    return make_scene

