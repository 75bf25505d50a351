"""Simulation engine: state layout, plant right-hand side, integrators, compiled loop, ``simulate``."""
