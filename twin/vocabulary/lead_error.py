"""The screw's lead error (ISO 3408-3): its entries in the model's vocabulary (:mod:`twin.layout`)."""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e
from twin.vocabulary.entries import work as _w

DECLARATION = Component("lead_error", constants=(
    # the screw's travel deviation e(phi) of ISO 3408-3 (twin.physics.ball_screw.travel_deviation)
    _e("LEAD_SLOPE", "1", "mean travel deviation per unit travel s", "ball_screw.lead_mean_deviation_slope"),
    _e("LEAD_WAVE_AMPLITUDE", "m", "amplitude a_u of the long-wave travel variation",
       "ball_screw.lead_travel_variation_amplitude"),
    _e("LEAD_WAVE_NUMBER", "1/rad", "phase of the long-wave variation per rad of screw angle, p / lambda_u"),
    _e("LEAD_WAVE_PHASE", "rad", "phase phi_u of the long-wave variation at the test zero",
       "ball_screw.lead_travel_variation_phase"),
    _e("LEAD_WAVE_AT_ZERO", "1", "sin(phi_u): the long-wave term at the test zero, subtracted"),
    _e("LEAD_REVOLUTION_AMPLITUDE", "m", "amplitude of the nut's travel variation within one revolution: a_2pi "
                                         "averaged over the nut's balls (twin.engine.model.lead_constants)"),
    _e("LEAD_REVOLUTION_PHASE", "rad", "phase phi_2pi of the per-revolution variation at the test zero",
       "ball_screw.lead_per_revolution_phase"),
    _e("LEAD_REVOLUTION_AT_ZERO", "1", "sin(phi_2pi): the per-revolution term at the test zero, subtracted"),
), work=(
    _w("NUT_LEAD_SLOPE", "m/rad", "the lead error's rate e'(theta_s - theta_ni) at nut i", rows=2),
))
