"""Design limits on the loop margins: the campaign spec's optional ``[control_limits]`` table.

A light module (pydantic only), so the spec can validate the table without loading the analysis.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

__all__ = ["ControlLimits"]


class ControlLimits(BaseModel):
    """Design limits on the loop margins (the spec's optional ``[control_limits]`` table).

    Defaults are classic robustness rules for PI loops (Skogestad & Postlethwaite, *Multivariable
    Feedback Control*, 2005, Sec. 2.4.3: GM > 2 (6 dB), PM > 30 deg, ``|S|max`` < 2), documented in
    ``docs/control_design.md``. ``max_fraction_beyond`` is the fraction of sampled benches a design
    review accepts beyond a limit (the verdict's threshold).
    """

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)

    phase_margin_min: float = Field(default=30.0, gt=0.0, lt=180.0, description="phase margin limit [degree]")
    gain_margin_min: float = Field(default=6.0, gt=0.0, description="gain margin limit [dB]")
    peak_sensitivity_max: float = Field(default=2.0, gt=1.0, description="peak sensitivity |S|max limit [1]")
    max_fraction_beyond: float = Field(default=0.01, gt=0.0, lt=1.0,
                                       description="fraction of runs allowed beyond a limit [1]")
