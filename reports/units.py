"""Display units and number formatting shared by the figures and the tables.

Values are stored in SI units; a report shows them with the SI prefix that
suits their magnitude (backlash in µm, positions in mm, forces in N or kN) and
pressures in bar, the unit of the bench's pneumatic components. The rules live in
:mod:`campaigns.units` (the comparison's and the diagnosis's sentences, written below
the report, read the same way); this module adds the figures' axis labels.
"""

from __future__ import annotations

from campaigns.units import display_scale, estimate_with_interval, number, quantity, quantity_range

__all__ = ["axis_label", "display_scale", "estimate_with_interval", "number", "quantity", "quantity_range"]


def axis_label(name: str, unit: str) -> str:
    """``name [unit]``; dimensionless quantities get ``[–]``."""
    return f"{name} [{unit or '–'}]"
