"""The bench's vocabulary: the index layouts of every component's states, constants, signals and work rows.

Each component declares what it contributes in its leaf module of :mod:`twin.vocabulary` (a
:class:`~twin.vocabulary.entries.Component`): its continuous states, the model constants it reads (with the parameter
each copies, when it is one as it stands), the signals it records and the work rows it leaves for the rest of the
engine, each with its SI unit and meaning. A component with several instances (the two nuts) declares its entries
once with ``{n}`` in the name. The index layouts the compiled engine uses, :class:`S` (states), :class:`K`
(constants), :class:`Signal` and :class:`W` (work rows), are generated here from those declarations in the order of
:data:`twin.vocabulary.COMPONENTS`; numba treats ``IntEnum`` members as compile-time constants, so the compiled code
reads ``x[S.NUT1_POSITION]`` at no cost. ``docs/architecture.md`` shows what adding a component touches.
"""

from __future__ import annotations

from enum import IntEnum

from twin.features import FEATURES as FEATURE_TABLE
from twin.features import N_ACCUMULATORS
from twin.vocabulary import COMPONENTS
from twin.vocabulary.entries import Entry


def _expanded(kind: str) -> list[tuple[Entry, int]]:
    """Every entry of ``kind`` ("states", "constants", "signals") with its instance (0-based), in declaration order."""
    return [(entry, n) for component in COMPONENTS for n in range(component.instances)
            for entry in getattr(component, kind)]


def _layout(name: str, kind: str) -> type[IntEnum]:
    names = [entry.name.format(n=n + 1) for entry, n in _expanded(kind)]
    duplicates = sorted({x for x in names if names.count(x) > 1})
    if duplicates:
        raise ImportError(f"twin.layout: {kind} declared twice: {', '.join(duplicates)}")
    return IntEnum(name, {entry: k for k, entry in enumerate(names)})


S = _layout("S", "states")
S.__doc__ = "Continuous state vector (SI units), generated from :data:`COMPONENTS`."
K = _layout("K", "constants")
K.__doc__ = "Model constants (SI units), generated from :data:`COMPONENTS`; built by twin.engine.model."
Signal = _layout("Signal", "signals")
Signal.__doc__ = "Recorded output signals (one column each in the output buffer), generated from :data:`COMPONENTS`."


def _work_layout() -> type[IntEnum]:
    """The work rows: one member per declared row entry, its first row; an entry of ``rows`` rows takes as many."""
    members, row = {}, 0
    for component in COMPONENTS:
        for entry in component.work:
            if entry.name in members:
                raise ImportError(f"twin.layout: work row declared twice: {entry.name}")
            members[entry.name] = row
            row += entry.rows
    return IntEnum("W", members)


W = _work_layout()
W.__doc__ = ("Work rows of a lane group (``w[row, lane]``): what one right-hand-side evaluation leaves for the rest of "
             "the engine (recording, instruments, the guard), generated from :data:`COMPONENTS`. A per-nut member "
             "names its first nut's row, nut ``i``'s is the member plus ``i``.")
#: Rows of the work array.
N_WORK = sum(entry.rows for component in COMPONENTS for entry in component.work)

N_STATES = len(S)
N_CONSTANTS = len(K)
N_SIGNALS = len(Signal)

#: Unit and meaning of every state, constant and signal (``{layout member: (unit, description)}``).
STATE_META = {S[entry.name.format(n=n + 1)]: (entry.unit, entry.meaning(n)) for entry, n in _expanded("states")}
CONSTANT_META = {K[entry.name.format(n=n + 1)]: (entry.unit, entry.meaning(n)) for entry, n in _expanded("constants")}
SIGNAL_META = {Signal[entry.name.format(n=n + 1)]: (entry.unit, entry.meaning(n)) for entry, n in _expanded("signals")}

#: The model constants that are a parameter's value as it stands (``{K member: parameter name}``): the plain part of
#: the parameter -> model mapping, derived from the declarations. The others are computed by
#: :func:`twin.engine.model.build_model` (formulas, fidelity levels, scene conditions).
PARAMETER_CONSTANTS: dict = {
    K[entry.name.format(n=n + 1)]: (entry.parameter if isinstance(entry.parameter, str) else entry.parameter[n])
    for entry, n in _expanded("constants") if entry.parameter}

#: Per-nut strides: nut ``i``'s state (constant) is its first nut's member plus ``i * NUT_STATE_STRIDE``
#: (``i * NUT_CONSTANT_STRIDE``).
NUT_STATE_STRIDE = S.NUT2_POSITION - S.NUT1_POSITION
NUT_CONSTANT_STRIDE = K.NUT2_MASS - K.NUT1_MASS

# (position, velocity) pairs: the semi-implicit Euler integrator updates the
# velocity first and moves the position with the new velocity.
POSITION_VELOCITY_PAIRS = (
    (S.REDUCER_ANGLE, S.REDUCER_SPEED),
    (S.SCREW_ANGLE, S.SCREW_SPEED),
    (S.SCREW_AXIAL, S.SCREW_AXIAL_SPEED),
    (S.NUT1_POSITION, S.NUT1_SPEED),
    (S.NUT1_ANGLE, S.NUT1_ANGULAR_SPEED),
    (S.NUT2_POSITION, S.NUT2_SPEED),
    (S.NUT2_ANGLE, S.NUT2_ANGULAR_SPEED),
    (S.PISTON_POSITION, S.PISTON_SPEED),
)


class U(IntEnum):
    """Inputs held between controller samples (zero-order hold)."""

    CURRENT_DEMAND = 0     # speed-loop output [A]
    VALVE_COMMAND = 1      # effective valve command after D/A and hysteresis [V]


N_INPUTS = len(U)

# Scalar features of a run (twin.features), computed by the loop alongside the signals.
FEATURES = tuple(FEATURE_TABLE)
# Everything a scene or a campaign may ask a run to produce.
OUTPUT_NAMES = tuple(signal.name.lower() for signal in Signal) + FEATURES


class M(IntEnum):
    """Memory of the digital loops and the acquisition between samples."""

    POSITION_INTEGRAL = 0
    SPEED_INTEGRAL = 1
    FORCE_INTEGRAL = 2
    SPEED_COMMAND = 3       # after the drive's analog input [rad/s]
    PREVIOUS_ANGLE = 4      # resolver reading at the previous speed sample [rad]
    DEMAND = 5              # position demand at the last acquisition [m]
    SAMPLES = 6             # acquisition samples taken
    # last acquired readings, in the order of Signal.LINEAR_ENCODER_POSITION ...
    SLED = 7
    SCREW_ANGLE = 8
    SLED_SPEED = 9
    MOTOR_SPEED = 10
    CURRENT = 11
    TORQUE = 12
    PRELOAD = 13
    EXTERNAL = 14
    FORCE_FEEDBACK = 15     # the load-cell reading the force loop acts on [N] (scene condition noise_path)
    LOCAL_ERROR = 16        # largest step-doubling local-error estimate so far, in tolerance units
    LOCAL_ERROR_STREAK = 17  # consecutive acquisition instants with the estimate above tolerance
    # feature accumulators (layout twin.features.A), from true and from measured signals
    FEATURES_TRUE = 18
    FEATURES_MEASURED = 18 + N_ACCUMULATORS


N_MEMORY = M.FEATURES_MEASURED + N_ACCUMULATORS
N_MEASURED = M.EXTERNAL - M.SLED + 1

# Run status codes returned by the compiled loop.
STATUS_OK = 0
STATUS_NONFINITE = 1
STATUS_OUT_OF_BOUNDS = 2
STATUS_SOLVER_FAILED = 3  # the scipy reference path's solver gave up
STATUS_TEXT = {STATUS_OK: "ok", STATUS_NONFINITE: "diverged", STATUS_OUT_OF_BOUNDS: "diverged",
               STATUS_SOLVER_FAILED: "failed"}

# Bound codes (which physical bound the guard tripped on).
BOUND_REASONS = {
    0: "",
    1: "non-finite state (NaN/inf)",
    2: "sled beyond the stroke limit",
    3: "motor speed beyond twice the maximum permissible speed",
    4: "motor current beyond five times the drive/motor maximum",
    5: "winding temperature beyond 200 degC",
    6: "ball-groove normal approach beyond the Hertzian validity bound",
    7: "chamber pressure outside [0, 2 x supply] (absolute)",
    8: "finite but wrong: the step-doubling local-error estimate exceeds its tolerance (step beyond stability)",
    9: "the quasi-static screw-axial balance did not converge",
}
