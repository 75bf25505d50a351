"""Numerics that give the same bits on every machine: the compiled code's foundations.

:mod:`numerics.elementary` (branch-free exp, expm1, log, tanh, sin, cos, x^0.26: the same bits whether a loop is
vectorised or not, on any x86-64 CPU), :mod:`numerics.linalg` (small dense linear algebra in a fixed operation
order), :mod:`numerics.jit` (the compile options of scalar physics functions and of lane kernels),
:mod:`numerics.compiled_cache` (numba's on-disk cache keyed on the sources) and :mod:`numerics.units` (the one
parser of units and of values written with one; pint, loaded on first use). The bottom layer: it imports nothing
of the project; ``sensors`` and ``twin`` build on it.
"""

# Key numba's cache on the source before anything is compiled (numerics.compiled_cache).
from numerics import compiled_cache

compiled_cache.configure()
