"""Measurement models of the bench sensors (Sec. 9.3, Table 9.5, Appendix B).

Compiled (numba) functions work on floats and on ``[row, lane]`` float64
parameter/state arrays (one column per Monte Carlo lane, :mod:`sensors.lanes`)
whose rows are documented in each module; they are branch-free and act on one
lane's column. Plain-Python builders validate the ``sensors`` parameter group and
pack one lane's parameter vector.

Modules: :mod:`sensors.encoder` (linear and torque-meter encoders),
:mod:`sensors.analog` (shared force/torque channel), :mod:`sensors.torque_meter`,
:mod:`sensors.load_cell`, :mod:`sensors.resolver`,
:mod:`sensors.acquisition` (converters, noise, uncertainty convention),
:mod:`sensors.parameters` (parameters as data), :mod:`sensors.lanes` (the lane
layout). Conventions: ``docs/sensors.md``.
"""

# numba's cache is keyed on the source before any sensor or twin module is compiled (numerics.compiled_cache).
import numerics  # noqa: F401
