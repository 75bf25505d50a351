"""How many units, and repeats per unit, a within-unit verdict needs (:mod:`campaigns.analysis.within_unit`): the
floors a spec's ``[units]`` table is checked against before anything runs."""

from __future__ import annotations

from campaigns.statistics.defaults import CONFIDENCE
from campaigns.statistics.order_statistics import min_runs_for_quantile_bound

#: Quantile of the unit population the verdict is about: the 95th-percentile unit (the 95/95 design-review figure).
DESIGN_REVIEW_QUANTILE = 0.95
#: Quantiles of the unit population reported: the median unit and the design-review unit.
UNIT_QUANTILES = (0.5, DESIGN_REVIEW_QUANTILE)
#: Ok repeats a unit needs at every level: 2 for a residual, 3 for the Brown-Forsythe check of the shared scatter
#: (the deviations of 2 repeats from their median are equal, so the test has no within-unit variation).
MIN_REPEATS = 3


def unit_floor(quantiles=UNIT_QUANTILES, confidence: float = CONFIDENCE) -> int:
    """Units every population statistic needs: :data:`MIN_UNITS` for the default settings.

    A quantile ``q`` of the per-unit figures has a distribution-free upper confidence bound among the units' order
    statistics only from :func:`campaigns.analysis.campaign_analysis.min_runs_for_quantile_bound` ``(q, confidence)``
    units on, and a lower one from ``(1 - q, confidence)`` units on (David & Nagaraja 2003, *Order Statistics*, 3rd
    ed., Sec. 7.1); the 95th-percentile unit binds: 59 units, the largest of which bounds it at 95 % (Wilks 1941).
    """
    return max(max(min_runs_for_quantile_bound(q, confidence), min_runs_for_quantile_bound(1.0 - q, confidence))
               for q in quantiles)


#: Units with :data:`MIN_REPEATS` at every level needed before any population statistic or verdict
#: (:func:`unit_floor`): 59 at 95 % confidence.
MIN_UNITS = unit_floor()
