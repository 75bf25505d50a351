"""Fidelity: model no more than a scene needs.

Each subsystem of the bench has named levels (:mod:`twin.levels`);
``fidelity="auto"`` picks, per subsystem, the cheapest level the scene's
demands, duration and requested outputs allow, by the rules of
``rules.toml`` (:mod:`twin.fidelity.rules`), and explains every choice.
``twin fidelity audit`` checks the choice against the full model
(:mod:`campaigns.bench.fidelity_audit`).
"""

from twin.fidelity.requests import full_plant, requested_levels
from twin.fidelity.rules import Fidelity, load_rules, resolve_fidelity
from twin.levels import SUBSYSTEMS, Level, Subsystem

__all__ = ["SUBSYSTEMS", "full_plant", "requested_levels", "Fidelity", "Level", "Subsystem", "load_rules",
           "resolve_fidelity"]
