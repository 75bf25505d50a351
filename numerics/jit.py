"""The compile options of the project's numba code, named once.

``SCALAR`` functions (physics laws, instruments, elementary functions) work on one sample's floats; they are
forced inline into their callers (LLVM ``alwaysinline``: without it a call stays a call and the caller's lane
loop cannot be vectorised; numba's own ``inline="always"`` inlines numba IR instead, at 5-10x the compile time,
and the loops built that way did not vectorise) and use ``error_model="numpy"``: a division by zero gives the
IEEE inf or nan instead of raising, so no zero check branches around every ``/`` (such a branch stops the
vectoriser; for finite nonzero divisors nothing changes).

``KERNEL`` functions run loops over the lanes of a group (struct of arrays ``[row, lane]``). They promise LLVM
that their array arguments do not overlap (``noalias``): without it LLVM guards each vectorised loop with run-time
overlap checks between every pair of rows, and then demands 12-92 iterations before the vector loop pays, which a
group of 8 or 16 lanes never has. numba has this flag internally (its parallel accelerator sets it) but does not
accept it as a ``jit`` option; :data:`NOALIAS_OPTION` registers it. A caller must never pass the same or
overlapping arrays to two arguments of a ``KERNEL`` function.

Neither allows ``fastmath``: LLVM then neither contracts a multiply-add into an FMA nor reorders a sum, so a
result depends only on its inputs, whatever the CPU's vector width (docs/campaigns.md, "The same numbers
everywhere").
"""

from numba.core import cpu, options

#: numba's internal ``noalias`` flag as a jit option (see the module docstring); registered once, at import.
NOALIAS_OPTION = "noalias"
if not hasattr(cpu.CPUTargetOptions, NOALIAS_OPTION):
    setattr(cpu.CPUTargetOptions, NOALIAS_OPTION, options.TargetOptions.Mapping(NOALIAS_OPTION))

#: Options of scalar functions (one sample): cached, inlined into the caller, IEEE division.
SCALAR = {"cache": True, "error_model": "numpy", "forceinline": True}
#: Options of lane kernels: cached, IEEE division, no bounds checks, arrays promised not to overlap.
KERNEL = {"cache": True, "error_model": "numpy", "boundscheck": False, NOALIAS_OPTION: True}
