"""The bench's components, each one module holding all of it (:mod:`twin.components.reducer` shows the parts).

:data:`COMPONENTS` is the one table of the components migrated so far: every component declared in
:data:`twin.vocabulary.COMPONENTS` (the registry, in the layouts' order) that has a module here,
``twin/components/<name>.py``, in that order. The engine's model derives their constants from it, the reference
integrator takes their states' tolerances, the energy balance sums their energies, and the right-hand side composes
their stages, split over the lanes and fused per lane, from :data:`FORCE_STAGES` and :data:`DERIVATIVE_STAGES`
(:mod:`twin.engine.plant`). The implicit
step's tangent and the loop design call a component's functions by name. The other parts of the bench are still
spread over ``twin/engine`` (docs/architecture.md, "Components").
"""

import importlib
import importlib.util

from twin.vocabulary import COMPONENTS as DECLARED

#: The migrated components' modules, in the layouts' order (found by name: ``twin.components.<declared name>``).
COMPONENTS = tuple(importlib.import_module(f"{__name__}.{declared.name}") for declared in DECLARED
                   if importlib.util.find_spec(f"{__name__}.{declared.name}") is not None)

#: The components' stages, each ``(active, stage)`` in the table's order, ``active(levels)`` whether the group's
#: fidelity levels keep the component: the forces phase (:func:`twin.engine.plant.internal_forces`),
#: ``forces_at(x, c, w, lane)``, the work rows it leaves for the others, and the derivatives phase (before the
#: engine's own stages), ``derivatives_at(x, c, u, w, dxdt, lane, levels)``, its states' derivatives. A component
#: takes part in a phase by defining the function; all are :data:`numerics.jit.SCALAR` functions of one lane.
FORCE_STAGES = tuple((component.active, component.forces_at) for component in COMPONENTS
                     if hasattr(component, "forces_at"))
DERIVATIVE_STAGES = tuple((component.active, component.derivatives_at) for component in COMPONENTS
                          if hasattr(component, "derivatives_at"))
