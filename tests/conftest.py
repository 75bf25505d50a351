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



@pytest.fixture(scope="session")
def measured_campaign(tmp_path_factory):
    """A small bench sweep campaign (analysed), the twin's hidden-backlash run written as a bench's CSV log, its
    mapping, and the imported measured test (``tests/measured_helpers.py``); built once for the measured-test, CLI
    and report tests."""
    from types import SimpleNamespace

    from measured_helpers import hidden_run, sweep_spec, write_bench_csv, write_mapping

    import campaigns
    from campaigns.runner.files import write_netcdf
    from campaigns.workflows.measured import import_measured

    root = tmp_path_factory.mktemp("measured")
    spec = sweep_spec(root)
    results = campaigns.run_campaign(campaigns.load_spec(spec), root / "campaign", workers=2, progress=False)
    campaigns.analyze(results)
    run = hidden_run(spec)
    csv = write_bench_csv(run, root / "bench_run.csv")
    mapping = write_mapping(root / "mapping.toml")
    test = write_netcdf(import_measured(csv, mapping), root / "bench_run_measured.nc", title="measured test",
                        history="tests/conftest.py")
    return SimpleNamespace(root=root, spec=spec, results=results, run=run, csv=csv, mapping=mapping, test=test)
