"""The test procedure as scene conditions: the zero procedure and the cylinder's state."""

import json

import numpy as np
import pytest

import twin
from twin.engine.codes import CONTACT
from twin.engine.model import build_model, contact_position_for_force
from twin.errors import OptionError, SceneError
from twin.fidelity import resolve_fidelity
from twin.layout import S
from twin.scenes import CONDITIONS


@pytest.mark.parametrize("name", [f"ds{k}" for k in range(1, 8)] + ["nominal"])
def test_thesis_scenes_use_the_thesis_procedure(name):
    scene = twin.load_scene(name)
    assert scene.condition("zero_procedure") == "thesis" and scene.condition("cylinder") == "attached"


def test_unstated_procedure_takes_the_documented_defaults(scene_factory):
    scene = scene_factory(1.0)
    assert scene.condition("zero_procedure") == CONDITIONS["zero_procedure"].default == "preloaded"
    assert scene.condition("cylinder") == CONDITIONS["cylinder"].default == "attached"


def test_bad_procedure_values_are_named_with_the_allowed_ones():
    with pytest.raises(SceneError) as error:
        twin.load_scene("ds2").with_conditions({"zero_procedure": "homed", "cylinder": "vented"})
    text = str(error.value)
    assert "conditions.zero_procedure: 'homed' is not one of thesis, preloaded" in text
    assert "conditions.cylinder: 'vented' is not one of attached, detached" in text


def test_detached_cylinder_cannot_apply_a_force_demand_nor_be_modelled():
    with pytest.raises(SceneError, match="conditions.cylinder"):
        twin.load_scene("ds3").with_conditions({"cylinder": "detached"})
    scene = twin.load_scene("ds2").with_conditions({"cylinder": "detached"})
    params = twin.load_parameters()
    with pytest.raises(OptionError, match="fidelity.pneumatics"):
        resolve_fidelity(scene, params, {"pneumatics": "full"})
    full = resolve_fidelity(scene, params, "full")  # the most detailed model of a bench without its cylinder
    assert full.level("pneumatics") == "absent" and "detached" in full.reasons["pneumatics"]


def test_thesis_procedure_starts_unloaded_and_the_springs_load_the_nuts(bench):
    """Sec. 9.3.2 / Fig. 9.7b: at t = 0 nothing is loaded but the disc springs, which push with the scene's
    preload; they then push the nuts b/2 onto their flanks and into the contact, and the preload relaxes to
    P_eq = P - k_pr (b + 2 delta_c(P_eq)) (each nut travels b/2 + delta_c). The preloaded procedure starts at
    P. Tolerance 1 %: the detached master nut stops wherever its guide friction (12 N) holds it."""
    scene = twin.load_scene("ds1").with_conditions({"cylinder": "detached"})
    model = build_model(scene, bench, resolve_fidelity(scene, bench))
    assert np.all(model.initial_state[[S.NUT1_POSITION, S.NUT2_POSITION, S.SCREW_ANGLE, S.SCREW_AXIAL]] == 0.0)
    ds = twin.simulate(scene, outputs=["preload_force"], duration=0.4)
    preload, backlash = scene.condition("preload"), scene.condition("backlash")
    assert float(ds.preload_force[0]) == pytest.approx(preload, rel=1e-9)
    stiffness = 1.0 / (1.0 / bench.value("preload.spring_stiffness") + 1.0 / bench.value("preload.load_cell_stiffness"))
    settled = preload
    for _ in range(50):
        deflection = contact_position_for_force(model.constants, int(model.levels[CONTACT]), settled) - 0.5 * backlash
        settled = preload - stiffness * (backlash + 2.0 * deflection)
    assert float(ds.preload_force[-1]) == pytest.approx(settled, rel=0.01)
    preloaded = twin.simulate(scene.with_conditions({"zero_procedure": "preloaded"}), outputs=["preload_force"],
                              duration=0.4)
    assert float(preloaded.preload_force[0]) == pytest.approx(preload, rel=1e-6)


def test_without_preload_the_procedures_coincide():
    """With no preload there is nothing to load at t = 0: the unloaded state is the equilibrium, so the thesis
    procedure and the preloaded zero run the same test (ds2: same f_b to the last bit). With a preload they
    do not (ds1: see tests/engine/test_backlash_features.py)."""
    runs = [twin.simulate(twin.load_scene("ds2").with_conditions({"zero_procedure": p}), duration=2.0, rng=0)
            for p in ("thesis", "preloaded")]
    assert float(runs[0].backlash_feature) == float(runs[1].backlash_feature)
    assert json.loads(runs[0].attrs["scene_conditions"])["zero_procedure"] == "thesis"
