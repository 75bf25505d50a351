"""Hall-effect current sensor of the drive's current loop (Sec. 9.3).

"The Hall effect sensors are represented through a simple first order transfer
function" (Sec. 9.3). The time constant is the drive's parameter
``drive.hall_time_constant``; unity gain (Table 9.5 lists no Hall sensor error).
"""

from __future__ import annotations

import numba

from numerics.jit import SCALAR
from sensors.acquisition import first_order_lag


@numba.njit(**SCALAR)
def hall_current_step(i_measured, i_start, i_end, dt, tau):
    """Measured current [A] after a step ``dt`` [s] of the true current from ``i_start`` to ``i_end``.

    Exact discretisation of ``tau di_m/dt + i_m = i`` with the true current
    linear over the step (:func:`sensors.acquisition.first_order_lag`).
    """
    return first_order_lag(i_measured, i_start, i_end, dt, tau)
