"""The free nut against the thesis's Ch. 7 (Sec. 7.9.3, Figs. 7.16-7.19): app/studies/chapter7.py.

One 0.55 s run of ``chapter7_backlash`` (a few seconds once the engine is compiled) and the static Fig. 7.19 curve.
"""

import numpy as np
import pytest

import twin
from app.studies.chapter7 import backlash_run, loop_width, preload_curve, reversals, support_friction

BACKLASH = 5.0e-5  # m, Sec. 7.9.3 and the scene chapter7_backlash


@pytest.fixture(scope="module")
def run():
    return backlash_run("chapter7_backlash")


def test_nut_stops_at_every_reversal_until_the_screw_has_crossed_the_gap(run):
    found = reversals(run)
    # 5 Hz for 0.5 s: four reversals of the screw inside the sinusoid
    assert found.sizes["reversal"] == 4
    # Fig. 7.16b: the nut stands while the screw turns round. The screw travels the gap plus the release and
    # retake of the drive chain's deflection under the ~47 N of sliding support friction (about 1.7 um each way;
    # docs/validation.md, "Validation of the free nut against the thesis's Chapter 7"): between b and b + 10 um.
    assert np.all(found.stop_duration > 5e-3)
    assert np.all((found.screw_travel_while_stopped > BACKLASH)
                  & (found.screw_travel_while_stopped < BACKLASH + 10e-6))
    # Fig. 7.16c: a no-force gap inside each stop; the stop outlasts it because the closed flank must first build
    # up the supports' static friction ("until the backlash gap is closed and the axial force overcomes the static
    # friction of the supports")
    assert np.all(found.force_free_duration > 0.0)
    assert np.all(found.force_free_duration < found.stop_duration)
    # Fig. 7.16d: the support friction peaks at the stops at the static level (master share of the 100 N total)
    master_static = 100.0 / 1.5
    assert np.all(np.abs(found.peak_support_friction / master_static - 1.0) < 0.05)


def test_loop_spans_the_backlash(run):
    # Fig. 7.17c: "the elastic deformation is negligible with respect to the gap size" without external force.
    # The twin adds twice the chain's deflection under the support friction: a few um, not more than 5.
    width = loop_width(run)
    assert BACKLASH < width < BACKLASH + 5e-6


def test_preload_curve_is_the_hertz_closed_form_with_the_gap():
    curve = preload_curve(points=121)
    dx = curve.displacement.values
    inside = dx <= BACKLASH / 2
    # no force anywhere in the gap (Fig. 7.19's flat start), force beyond it
    assert np.all(curve.force_variable_angle.values[inside] == 0.0)
    assert np.all(curve.force_variable_angle.values[~inside] > 0.0)
    # the run-time law (polynomial fit of K(alpha)) against Hertz evaluated directly: the fit's error, < 1e-5
    beyond = dx > BACKLASH / 2 + 0.5e-6
    for law in ("variable_angle", "design_angle"):
        np.testing.assert_allclose(curve[f"force_{law}"].values[beyond],
                                   curve[f"closed_form_{law}"].values[beyond], rtol=1e-5)
    # at the design angle the law is F ~ (dx - b/2)^1.5 exactly (Eq. 7.28 with a constant K); Eq. 9.4's growing
    # angle stiffens it
    gap = dx[beyond] - BACKLASH / 2
    force = curve.force_design_angle.values[beyond]
    np.testing.assert_allclose(force / gap**1.5, force[0] / gap[0] ** 1.5, rtol=1e-9)
    assert np.all(curve.force_variable_angle.values[beyond] >= force)


def test_support_friction_override_keeps_the_thesis_total():
    params = twin.load_parameters("bench")
    share = params.value("sled.slave_friction_fraction")
    overrides = support_friction(params)
    assert overrides["sled.guide_friction_static"] * (1 + share) == pytest.approx(100.0)
    assert overrides["sled.guide_friction_dynamic"] * (1 + share) == pytest.approx(70.0)
