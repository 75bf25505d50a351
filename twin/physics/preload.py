"""Preload system: Belleville spring set in series with the preload load cell (Secs. 9.2-9.3)."""

import numba

from numerics.jit import SCALAR
from twin.physics.hertz import saturated_damping_force


@numba.njit(cache=True)
def series_stiffness(k_spring, k_load_cell):
    """Equivalent stiffness of the disc-spring set in series with the load cell [N/m]."""
    return 1.0 / (1.0 / k_spring + 1.0 / k_load_cell)


@numba.njit(**SCALAR)
def preload_force(separation, separation_rate, initial_compression, stiffness, damping, orientation):
    """One-directional preload force between the nuts (Sec. 9.3 "Preload load cell").

    The disc springs can only push (O configuration, ``orientation = +1``:
    nuts pushed apart) or only pull (X configuration, ``orientation = -1``:
    nuts drawn together), so the force saturates at zero (the thesis's "force
    saturated at zero").

    Parameters
    ----------
    separation : float
        ``x_n2 - x_n1`` relative to the assembled position [m].
    separation_rate : float
        Its rate [m/s].
    initial_compression : float
        Spring-set compression at zero separation [m]; sets the preload.
    stiffness, damping : float
        Series stiffness [N/m] and damping [N s/m].
    orientation : float
        +1 (O) or -1 (X).

    Returns
    -------
    float
        Magnitude ``F_pr >= 0`` of the preload; it acts as ``+orientation*F_pr``
        on the slave nut and ``-orientation*F_pr`` on the master (Eq. 9.8).
    """
    compression = initial_compression - orientation * separation
    elastic = stiffness * compression
    force = elastic + saturated_damping_force(elastic, damping, -orientation * separation_rate)
    return force if compression > 0.0 else 0.0
