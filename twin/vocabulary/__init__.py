"""The components' declarations: what each part of the bench contributes to the model's vocabulary, one leaf module
per component, registered here in the order of the layouts.

A component's module here (``twin/vocabulary/<name>.py``, ``DECLARATION``: its states, the constants it reads with
the parameter each copies, its signals and work rows, :class:`~twin.vocabulary.entries.Component`) imports nothing
but :mod:`twin.vocabulary.entries`. :mod:`twin.layout` generates the index layouts ``S``, ``K``, ``Signal`` and ``W``
from :data:`COMPONENTS`; the component's code (``twin/components/<name>.py``, where it has been migrated) indexes
the arrays with them. The declarations are a module of their own because the code's numba functions read ``K`` and
``S`` as compile-time constants from their module's globals: a declaration in the same module would make the layout
import the module that imports the layout (docs/architecture.md, "Components").
"""

from twin.vocabulary import (
    ball_groove_friction,
    ball_screw_contact,
    cylinder,
    drive,
    guides,
    instruments,
    lead_error,
    motor,
    nut,
    position_loop,
    preload,
    reducer,
    screw,
    seal,
    valve,
)

#: Every component's declaration, in the order of the layouts (a state's, constant's, signal's or work row's index).
COMPONENTS = tuple(module.DECLARATION for module in (
    motor, reducer, screw, nut, guides, ball_screw_contact, lead_error, ball_groove_friction, preload, drive,
    position_loop, valve, cylinder, seal, instruments))
