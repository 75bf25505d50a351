"""The bench's components, each one module holding all of it (:mod:`twin.components.reducer` shows the parts).

:data:`COMPONENTS` is the one table of the components migrated so far, in the layouts' order:
the engine's model derives their constants from it, the reference integrator takes their states' tolerances, the
energy balance sums their energies. The engine's compiled stages and the loop design call a component's functions by
name (numba compiles calls, not tables). The other parts of the bench are still spread over ``twin/engine``
(docs/architecture.md, "Components").
"""

from twin.components import preload, reducer

COMPONENTS = (reducer, preload)
