"""``encoder_advance`` (the loop's encoder stepping, which skips steps that cannot cross an edge) reads exactly
like ``encoder_step`` at every step, on a bench-like trajectory and on one five times faster."""

import numpy as np
import pytest

from sensors.encoder import (
    ENC_S_PEAK_FREQUENCY,
    ENC_S_U_STALE,
    ENC_STATE_SIZE,
    encoder_advance,
    encoder_init,
    encoder_parameters,
    encoder_reading,
    encoder_speed,
    encoder_step,
)

DT = 6.25e-5
SAMPLE_EVERY = 16  # 1 ms acquisition, as in the loop
#: The state slots both functions keep (encoder_advance adds its own after these; it does not track the peak).
SHARED = [j for j in range(ENC_S_PEAK_FREQUENCY)]


@pytest.fixture(scope="module")
def trajectory():
    """Sled position and screw angle at every 62.5 us step of a 3 s test shaped like the nominal scene's start:
    a hold, a 5 mm 1 Hz raised-cosine stroke (up to 31 mm/s, one to two edges per step), a hold; with the
    few-nanometre dither of a position loop holding still."""
    t = np.arange(round(3.0 / DT) + 1) * DT
    moving = (t > 0.5) & (t < 2.5)
    sled = np.where(moving, 5e-3 * (1.0 - np.cos(2.0 * np.pi * (t - 0.5))) / 2.0, 0.0)
    sled = sled + 3e-9 * np.random.default_rng(4).standard_normal(t.size)
    lead_arm = 5e-3 / (2.0 * np.pi)
    return sled, sled / lead_arm


def _dense_and_lazy(x, p):
    """Step one encoder state with encoder_step and another with encoder_advance; compare every reading."""
    dense, lazy = np.zeros(ENC_STATE_SIZE), np.zeros(ENC_STATE_SIZE)
    encoder_init(dense, x[0], 0.0, p)
    encoder_init(lazy, x[0], 0.0, p)
    skipped = 0
    for k in range(1, x.size):
        t = k * DT
        encoder_step(dense, x[k], t, p)
        encoder_advance(lazy, x[k], t, p)
        skipped += lazy[ENC_S_U_STALE] != 0.0
        assert encoder_reading(lazy, p) == encoder_reading(dense, p)
        if k % SAMPLE_EVERY == 0:
            assert encoder_speed(lazy, t, p) == encoder_speed(dense, t, p)
        if lazy[ENC_S_U_STALE] == 0.0:  # the scale position is only brought up to date when used
            assert np.array_equal(lazy[SHARED], dense[SHARED])
    return skipped


@pytest.mark.parametrize("speed_up", [1.0, 5.0])
@pytest.mark.parametrize("fidelity", [1, 2])
def test_advance_reads_like_stepping_at_every_step(trajectory, fidelity, speed_up):
    sled, angle = trajectory
    errors = dict(phase_error=0.6, asymmetry_a=-0.2, asymmetry_b=0.25, precision_amplitude=4e-6,
                  precision_wavelength=1e-3)
    linear = encoder_parameters(resolution=1e-6, timer_period=2.5e-8, fidelity=fidelity, **errors)
    rotary = encoder_parameters(resolution=2 * np.pi / 8000, timer_period=2.5e-8, fidelity=fidelity,
                                phase_error=-0.5, asymmetry_a=0.2, asymmetry_b=-0.1)
    # time runs speed_up times faster over the same path: more edges per step, down to several
    skipped = _dense_and_lazy(0.1 + speed_up * (sled - sled[0]), linear)
    skipped += _dense_and_lazy(speed_up * angle, rotary)
    assert skipped > 0.1 * sled.size  # the holds are skipped: the saving is real


def test_advance_never_skips_a_step_onto_an_edge():
    """A position that dithers across one edge by a few ulps: every crossing is counted."""
    p = encoder_parameters(resolution=1e-6, timer_period=2.5e-8, fidelity=1)
    edge = 37e-6
    x = edge + np.array([-1, 1, -1, 0, 2, -2, 1e6, -1e6] * 50) * np.spacing(edge)
    _dense_and_lazy(np.concatenate([[edge - 0.4e-6], x]), p)
