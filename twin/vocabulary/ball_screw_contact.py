"""The ball-groove contact of the two nuts (Eqs. 9.4-9.6, 5.5):
its entries in the model's vocabulary (:mod:`twin.layout`).
"""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e
from twin.vocabulary.entries import work as _w

DECLARATION = Component("ball_screw_contact", constants=(
    _e("LEAD_ARM", "m/rad", "p(T) / (2 pi): the lead of the screw at the room temperature (Eq. 7.72)"),
    _e("LEAD_ARM_NOMINAL", "m/rad", "p / (2 pi) of the nominal lead: Eq. 9.12's screw equivalent position"),
    _e("COS_HELIX", "1", "cos(alpha_e)"),
    _e("SIN_HELIX", "1", "sin(alpha_e)"),
    _e("CENTRE_DISTANCE", "m", "A0, distance of the groove curvature centres at first contact (Eq. 9.4)"),
    _e("CONTACT_ANGLE_0", "rad", "design contact angle alpha_0", "ball_screw.contact_angle"),
    _e("CONTACT_RADIAL_0", "m", "A0 cos(alpha_0)"),
    _e("CONTACT_AXIAL_0", "m", "A0 sin(alpha_0)"),
    _e("SIN_ALPHA_0", "1", "sin(alpha_0)"),
    _e("SIN_ALPHA_MIN", "1", "lower end of the stiffness fit's sin(alpha) range"),
    _e("SIN_ALPHA_SPAN", "1", "width of the stiffness fit's sin(alpha) range"),
    *(_e(f"STIFFNESS_C{k}", "N/m^1.5", f"coefficient {k} of the series Hertz stiffness fit K(sin alpha)")
      for k in range(7)),
    _e("CONTACT_DAMPING", "s/m^0.25", "contact damping b_h (Eq. 7.54)", "ball_screw.contact_damping_coefficient"),
    _e("LOADED_BALLS", "1", "loaded spheres Z_eff (Eq. 5.5)"),
    _e("BACKLASH", "m", "axial backlash of each nut (scene condition)"),
    _e("LINEAR_CONTACT_STIFFNESS", "N/m", "normal stiffness per sphere of the linear contact level"),
    _e("MAX_NORMAL_APPROACH", "m", "Hertzian validity bound of the normal approach (divergence guard)"),
), work=(
    _w("NUT_FORCE", "N", "axial force of the screw on nut i (Eqs. 9.4-9.6)", rows=2),
    _w("NUT_NORMAL", "N", "normal load per sphere of nut i", rows=2),
    _w("NUT_DX", "m", "relative position dx_i (Eq. 9.5)", rows=2),
    _w("NUT_DV", "m/s", "its rate", rows=2),
))
