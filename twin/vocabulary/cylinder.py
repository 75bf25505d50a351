"""The pneumatic cylinder, its end stops and the external load cell (Eqs. 9.10-9.11):
its entries in the model's vocabulary (:mod:`twin.layout`).
"""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e
from twin.vocabulary.entries import work as _w

DECLARATION = Component("cylinder", states=(
    _e("CHAMBER1_PRESSURE", "Pa", "cap-side chamber pressure, absolute"),
    _e("CHAMBER2_PRESSURE", "Pa", "rod-side chamber pressure, absolute"),
    _e("PISTON_POSITION", "m", "piston position from the cap-end stop"),
    _e("PISTON_SPEED", "m/s", "piston speed"),
), constants=(
    *(_e(name, unit, description) for name, unit, description in (
        ("P_SUPPLY", "Pa", "supply pressure (scene condition)"), ("P_ATMOSPHERE", "Pa", "exhaust pressure"),
        ("AIR_TEMPERATURE", "K", "air temperature (the room's)"), ("GAS_CONSTANT", "J/(kg K)", "air gas constant"),
        ("POLYTROPIC_EXPONENT", "1", "polytropic exponent"), ("REFERENCE_DENSITY", "kg/m3", "ISO 6358 rho_0"),
        ("REFERENCE_TEMPERATURE", "K", "ISO 6358 T_0"), ("MAX_CONDUCTANCE", "m3/(s Pa)", "fully open conductance"),
        ("LEAKAGE_FRACTION", "1", "centre leakage fraction"), ("CRITICAL_RATIO", "1", "critical pressure ratio b"),
        ("LAMINAR_RATIO", "1", "laminar band ratio"), ("AREA1", "m2", "cap-side area"),
        ("AREA2", "m2", "rod-side area"),
        ("DEAD_VOLUME1", "m3", "cap-side dead volume"), ("DEAD_VOLUME2", "m3", "rod-side dead volume"),
        ("STROKE", "m", "cylinder stroke"), ("PISTON_MASS", "kg", "piston, rod, rod end and load cell"),
        ("PISTON_DAMPING", "N s/m", "piston damping"),
        ("DAMPER_STIFFNESS", "N/m", "end-stroke damper stiffness"), ("DAMPER_TRAVEL", "m", "damper travel"),
        ("DAMPER_DAMPING", "N s/m", "damper damping"), ("END_STOP_STIFFNESS", "N/m", "end-stop stiffness"),
        ("LOAD_CELL_STIFFNESS", "N/m", "external load cell stiffness"),
        ("LOAD_CELL_DAMPING", "N s/m", "external load cell damping"),
        ("LINK_OFFSET", "m", "piston position minus sled position at zero load-cell force"))),
), signals=(
    _e("EXTERNAL_FORCE", "N", "external force on the master nut"),
    _e("CHAMBER1_PRESSURE", "Pa", "cylinder cap-side chamber pressure (absolute)"),
    _e("CHAMBER2_PRESSURE", "Pa", "cylinder rod-side chamber pressure (absolute)"),
    _e("PISTON_POSITION", "m", "piston position from the cap-end stop"),
), work=(
    _w("EXTERNAL", "N", "external force on the master nut"),
))
