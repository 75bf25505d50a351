"""Resolved uncertainties: one distribution per row of a spec's uncertainty table, in SI units.

The spec (:mod:`campaigns.runner.spec`) resolves its rows into :class:`Distribution` objects; the sampler
(:mod:`campaigns.runner.sampling`) draws from them. This module sits below both, so the sampler (imported by
every run process) does not import the spec's schema.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Literal

DistributionKind = Literal["gaussian", "truncated_gaussian", "uniform", "constant", "lognormal"]


@dataclass(frozen=True)
class Distribution:
    """One resolved uncertainty: absolute parameters in the target's SI unit.

    Attributes
    ----------
    target : str
        Parameter name or ``scene.<condition>``.
    kind : str
        One of :data:`DistributionKind`.
    unit : str
        SI unit of the sampled value (the parameter set's unit).
    nominal : float
        Nominal value of the target.
    mean, sigma : float
        Gaussian / truncated-Gaussian location and scale; for ``lognormal``
        ``mean`` is the median and ``sigma`` the standard deviation of the log.
    low, high : float
        Uniform bounds, truncation bounds; NaN when unused.
    value : float
        The ``constant`` value; NaN otherwise.
    source : str
        Where the row comes from (e.g. the Table 9.5 row).
    """

    target: str
    kind: str
    unit: str
    nominal: float
    mean: float = math.nan
    sigma: float = math.nan
    low: float = math.nan
    high: float = math.nan
    value: float = math.nan
    source: str = ""

    def as_dict(self) -> dict:
        """JSON-ready dictionary (NaN fields omitted)."""
        return {k: v for k, v in asdict(self).items() if not (isinstance(v, float) and math.isnan(v))}
