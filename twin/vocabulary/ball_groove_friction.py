"""The ball-groove friction (Eqs. 5.16-5.25): its entries in the model's vocabulary (:mod:`twin.layout`)."""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e
from twin.vocabulary.entries import work as _w

DECLARATION = Component("ball_groove_friction", constants=(
    *(_e(f"FRICTION_G{k}", unit, f"Eq. 5.16 coefficient g_{k}", f"ball_screw.sliding_friction_g{k}")
      for k, unit in ((1, "1"), (2, "s/m"), (3, "s/m"), (4, "1"), (5, "s/m"), (6, "s/m"))),
    _e("ROLLING_K_GC", "m/N^0.26", "rolling load coefficient (Eqs. 5.20-5.23)",
       "ball_screw.rolling_friction_load_coefficient"),
    _e("ROLLING_K_RF", "1", "rolling friction multiplier k_rf", "ball_screw.rolling_friction_multiplier"),
    _e("ROLLING_F_V1", "s2", "rolling speed coefficient (Eqs. 5.19/5.21)",
       "ball_screw.rolling_friction_speed_coefficient"),
    _e("ROLLING_THRESHOLD", "m/s", "direction regularisation of the rolling term",
       "ball_screw.rolling_friction_direction_threshold"),
    _e("BALL_RADIUS", "m", "ball radius r_b", "ball_screw.ball_radius"),
    _e("PITCH_RADIUS", "m", "pitch radius r_m", "ball_screw.pitch_radius"),
), signals=(
    _e("BALL_GROOVE_FRICTION_TORQUE", "N m", "ball-groove friction torque opposing the screw rotation, both nuts "
                                             "(Eqs. 5.16-5.24; the drag torque, Eq. 7.85, without external force)"),
    _e("BALL_SCREW_EFFICIENCY", "1", "ball-screw mechanical efficiency (Eq. 5.25): P_out/P_in driving, "
                                     "-P_in/P_out back-driving, 0 at rest or when both powers enter"),
), work=(
    _w("NUT_FRICTION", "N", "helix friction force of nut i along v_t (reduced Ch. 5)", rows=2),
))
