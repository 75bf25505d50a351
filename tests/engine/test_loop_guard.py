"""The divergence guard's short cuts decide exactly like the plain checks they replace."""

import math

import numpy as np
import pytest

import twin
from twin.engine.loop import _sum_is_finite, guard
from twin.engine.model import build_model
from twin.engine.plant import nut_relative_position
from twin.fidelity import resolve_fidelity
from twin.layout import K, S
from twin.physics.ball_screw import contact_geometry


@pytest.mark.parametrize("values", [
    [0.0, -1.5, 3e5], [math.inf, 0.0], [-math.inf, 1.0], [math.nan], [1e308, 1e308], [-1e308, 1e308],
    [1.7e308, -1e300, 1e2], [2.0 ** 977, 2.0 ** 977], [5e-324, -0.0], [math.inf, -math.inf],
])
def test_finite_check_is_the_finiteness_of_the_sum(values):
    x = np.array(values * 3, dtype=float)
    assert _sum_is_finite(x) == math.isfinite(sum(x.tolist()))


def test_approach_limit_decided_by_the_exact_contact_geometry(bench):
    """Interferences up to and past the normal-approach limit: code 6 exactly where Eq. 9.4 exceeds it."""
    scene = twin.load_scene("ds2")
    model = build_model(scene, bench, resolve_fidelity(scene, bench, "full", None, "thesis"))
    c = model.constants
    limit = c[K.MAX_NORMAL_APPROACH]
    codes = []
    for interference in np.linspace(0.5, 1.5, 2001) * limit * 1.4:
        x = model.initial_state.copy()
        x[S.SCREW_AXIAL] = 0.0
        base = nut_relative_position(x, c, 0)
        x[S.SCREW_AXIAL] = interference / c[K.COS_HELIX] + 0.5 * c[K.BACKLASH] - base
        gap = abs(nut_relative_position(x, c, 0)) - 0.5 * c[K.BACKLASH]
        approach, _ = contact_geometry(gap * c[K.COS_HELIX], c[K.CENTRE_DISTANCE], c[K.CONTACT_RADIAL_0],
                                       c[K.CONTACT_AXIAL_0])
        code = guard(x, c)
        assert code in (0, 6)
        assert (code == 6) == (approach > limit)
        codes.append(code)
    assert 0 < codes.count(6) < len(codes)  # both sides of the limit were tried
