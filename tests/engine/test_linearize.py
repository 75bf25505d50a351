"""Step limits from eigenvalues (twin.engine.linearize.largest_stable_step) against closed forms."""

import numpy as np
import pytest

from twin.engine.linearize import RK4_STABILITY, largest_stable_step

FORWARD_EULER = np.polynomial.Polynomial([1.0, 1.0])


def test_rk4_reaches_two_root_two_on_the_imaginary_axis():
    # |R(iy)|^2 = 1 - y^6/72 + y^8/576 <= 1 exactly for y^2 <= 8 (Hairer & Wanner II, Sec. IV.2).
    omega = 2.6e4
    assert largest_stable_step([1j * omega, -1j * omega]) * omega == pytest.approx(2.0 * np.sqrt(2.0), rel=1e-11)


def test_rk4_real_axis_limit_is_the_real_root_of_r_minus_one():
    # RK4's R stays positive on the real axis, so the region ends where R(x) = +1 again: the one non-zero real
    # root of R - 1, an independent computation.
    roots = (RK4_STABILITY - 1.0).roots()
    real_root = min(r.real for r in roots if abs(r.imag) < 1e-9)
    assert largest_stable_step([-2.28e4]) * 2.28e4 == pytest.approx(-real_root, rel=1e-11)
    assert -real_root == pytest.approx(2.7853, abs=1e-4)


def test_forward_euler_limit_off_the_axis_is_two_a_over_lambda_squared():
    # |1 + h lambda| <= 1 with lambda = -a + i b holds for h <= 2 a / |lambda|^2: a ray that is not an axis.
    lam = -5.9e3 + 2.6e4j
    assert largest_stable_step([lam], FORWARD_EULER) == pytest.approx(2 * 5.9e3 / abs(lam) ** 2, rel=1e-11)


def test_the_most_limiting_eigenvalue_sets_the_step():
    modes = [-1e3, -5.9e3 + 2.6e4j, -5.9e3 - 2.6e4j, -2.28e4]
    # all rays bisected at once against one at a time: the same limit to the bisection's tolerance
    assert largest_stable_step(modes) == pytest.approx(min(largest_stable_step([m]) for m in modes), rel=1e-11)
    # the lightly damped contact pair of docs/performance.md limits RK4 to ~110 us: 62.5 us is stable, 125 not
    assert 62.5e-6 < largest_stable_step(modes) < 125e-6


def test_rigid_and_growing_modes_set_no_limit():
    assert largest_stable_step([0.0, 3.0, 2.0 + 5.0j]) == np.inf
    assert largest_stable_step([]) == np.inf
    # a finite-difference oscillation with a rounding-size positive real part is judged on the imaginary axis
    assert largest_stable_step([1e-3 + 1e4j]) == pytest.approx(largest_stable_step([1e4j]), rel=1e-11)
