"""Within-unit detection: the smallest fault growth a unit's own tests reveal while it wears (issue 29, part 2).

The observability sweep of :mod:`campaigns.analysis.observability` answers a between-unit question: every run draws
fresh tolerances, so its threshold separates one unknown unit from a population of healthy ones. A PHM bench tests the
same unit repeatedly: that unit's fixed errors (encoder phase errors, sensitivities, lead error) stay fixed, and
only test-to-test uncertainties (room temperature, supply pressure, the encoders' mounting phases, electrical noise)
change (which rows are which: docs/campaigns.md, "Within-unit campaigns"). The data of a within-unit campaign are
``values[level, unit, repeat]``: ``U`` units (tolerances drawn once per unit), tested at fault sizes ``levels`` (the
first, 0, is the unit's own baseline) with ``R`` repeats per level that redraw only the test-to-test uncertainties.
Non-finite values are failed runs: excluded and counted.

The rule: a unit's threshold from its own baseline and a scatter pooled over units
--------------------------------------------------------------------------------------
The detection rule of the analysis, applied to one unit alone, sets the unit's threshold at the
``1 - false_alarm_rate`` quantile of its own baseline tests. Taken empirically from the unit's repeats, that
quantile has a distribution-free confidence bound only from 59 repeats on
(:func:`campaigns.statistics.order_statistics.detection_run_floor`), so a campaign would need ``U x L x 59`` runs. With
the 5-20 repeats a bench affords, the empirical quantile lies between the unit's two largest tests, beyond which a fresh
baseline test falls with expected probability ``2 / (R + 1)`` and ``1 / (R + 1)`` (``E[F(X_(r))] = r / (R + 1)``):
a false-alarm rate well above the nominal one, and different for every unit.

This module assumes instead that **the test-to-test distribution at a fault level is shared by the units**: a unit
differs from another by its fixed errors (which move its feature's mean), not by how its tests scatter (which comes
from the test conditions, redrawn the same way for every unit). Under that assumption the baseline residuals of all
units (each unit's own baseline mean removed) estimate one scatter ``s_0`` with ``sum(n_u - 1)`` degrees of freedom,
and a unit's threshold is the normal prediction bound of one future baseline test (Meeker, Hahn & Escobar 2017,
*Statistical Intervals*, 2nd ed., Ch. 4)::

    threshold_u = mean_u,0 +/- t(1 - false_alarm_rate; sum(n_u,0 - 1)) * s_0 * sqrt(1 + 1 / n_u,0)

whose false-alarm rate is ``false_alarm_rate`` over the units' baselines, at any number of repeats, because the
bound carries the uncertainty of the unit's own baseline mean (the ``1 / n_u,0``) and of the pooled scatter (the
Student quantile). A test at fault size ``l`` is flagged with probability
``Phi((|mean_u,l - mean_u,0| - t s_0 sqrt(1 + 1/n_u,0)) / s_l)``, with ``s_l`` the scatter at that level pooled over
units the same way (the threshold on the side of the shift, as
:func:`campaigns.statistics.detection.detection_probability` judges by the medians), and the unit's minimum
detectable growth is where that probability reaches ``power``
(:func:`campaigns.statistics.detection.minimum_detectable`, the sweep levels bracketing it). With a known unit
mean and scatter it would be ``(z(1 - false_alarm_rate) + z(power)) sigma / k`` for a feature of sensitivity ``k`` per
unit of fault; with the baseline mean of ``R`` repeats, the median unit's is ``(z(1 - false_alarm_rate) sqrt(1 + 1/R) +
z(power)) sigma / k`` (many units: ``t`` tends to ``z``).

The assumption is checked, never silently trusted: at every level, the Brown-Forsythe test of equal variances
across units (Levene's test on deviations from each unit's median, Brown & Forsythe 1974, J. Am. Stat. Assoc.
69:364-367; ``scipy.stats.levene(center="median")``) and the D'Agostino-Pearson test of normality of the pooled
residuals (D'Agostino & Pearson 1973, Biometrika 60:613-622; ``scipy.stats.normaltest``), the model-adequacy checks
of a one-way layout (Montgomery 2017, *Design and Analysis of Experiments*, 9th ed., Sec. 3.4). Their p-values are
stored and the sentence says whether either rejects at :data:`CHECK_SIGNIFICANCE` (Bonferroni over the levels).

Over units: the median unit and the design-review unit
------------------------------------------------------
The per-unit minimum detectable growths form a distribution over the unit population. The median unit says what a
typical unit achieves; the **95th-percentile unit** is the design-review figure: the requirement applies to every
unit built, and "95 % of units detect a growth of at most X, with 95 % confidence" is the 95/95 statement of
qualification by statistics (Wilks 1941, Ann. Math. Stat. 12:91-96; Guba, Makai & Pal 2003, Reliab. Eng. Syst. Saf.
80:217-232), the same 95 % as the power and the confidence of the between-unit verdict. The verdict is computed once,
from that unit's bounds (:func:`campaigns.statistics.detection.requirement_verdict`).

The bounds resample units, not repeats: in a two-level design, resampling the top-level units with replacement and
keeping each unit's tests intact reproduces both levels of variation, while resampling the repeats as well counts the
within-unit variation twice (Davison & Hinkley 1997, *Bootstrap Methods and their Application*, Sec. 3.8; Ren et al.
2010, J. Appl. Stat. 37:1487-1498). Each replicate recomputes the pooled scatters from its resampled units, so their
uncertainty, shared by all units, enters the bounds. As in
:func:`campaigns.statistics.detection.bootstrap_minimum_detectable`, the bounds are sweep levels: order
statistics of the replicates' last level not detected and first level detected (``inf``: not reached), widened to
contain the bracket of the estimate. A percentile bootstrap of an upper quantile never goes beyond the largest unit,
which bounds the 95th-percentile unit with less than the stated confidence in small samples, so the bounds are also
widened to the distribution-free order-statistic bounds of the quantile
(:func:`campaigns.statistics.order_statistics.quantile_bound_rank`).

A unit's figure is that of its own threshold, set from its ``R`` baseline tests as the bench would set it in
service, so the scatter of the baseline mean (``sigma / sqrt(R)``) is part of the units' true spread. Its detection
probabilities, however, are estimated from ``R`` tests at each level, whose mean adds a scatter of about
``sigma / (k sqrt(R))`` to each unit's figure (for a location shift of sensitivity ``k``) that a unit in service does
not have: the 95th-percentile unit of the estimates lies above that of the true figures. A ``met`` verdict is
therefore conservative, and a ``not met`` close to the requirement may be one that more repeats would reverse.

Floors
------
:data:`MIN_UNITS`: units with every level tested enough, from the order statistics of the unit population:
with fewer, not even the largest unit bounds the 95th-percentile unit from above with 95 % confidence
(:func:`unit_floor`). :data:`MIN_REPEATS`: ok repeats of a unit at every level. A residual needs 2 (the unit's mean
removed), and the check of the shared scatter needs 3: the deviations of 2 repeats from their median are equal (half
their difference), so a Brown-Forsythe test of 2-repeat units has no within-unit variation to compare with. The rule
itself is valid from there on; more repeats shrink the estimation noise above.

In a campaign
-------------
A spec with ``[units]`` (:class:`campaigns.runner.spec.Units`) runs the units' tests at every level of its observability
sweep; :func:`unit_values` reads ``values[level, unit, repeat]`` from its ``results.nc`` and
:func:`within_unit_analysis` adds this module's variables, per feature, to ``analysis.nc``
(:func:`campaigns.analysis.campaign_analysis.analysis_dataset`), whose between-unit sweep then uses one test per unit.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from scipy import stats

from campaigns.analysis.settings import WITHIN_UNIT_STREAM, AnalysisSettings
from campaigns.analysis.vocabulary import (
    BACKLASH_REQUIREMENT,
    REQUIREMENT_SOURCE,
    SWEEP_QUANTITIES,
    features_of,
    is_within_unit,
    requirement_of,
    stored_spec,
    sweep_levels,
)
from campaigns.analysis.vocabulary import used as ok_runs
from campaigns.statistics.defaults import CONFIDENCE, FALSE_ALARM_RATE, POWER
from campaigns.statistics.detection import (
    RESOLUTIONS,
    minimum_detectable,
    printed_estimate,
    requirement_verdict,
    sweep_resolution,
)
from campaigns.statistics.order_statistics import quantile_bound_rank
from campaigns.statistics.within_unit_floors import DESIGN_REVIEW_QUANTILE, MIN_REPEATS, UNIT_QUANTILES, unit_floor
from campaigns.units import feature_units

#: Significance level of the checks of the shared test-to-test distribution (Bonferroni over the levels).
CHECK_SIGNIFICANCE = 0.05


def _checked(levels, values) -> tuple[np.ndarray, np.ndarray]:
    """``levels`` and ``values`` as float arrays, or one ValueError naming the argument and what is allowed."""
    try:
        levels = np.asarray(levels, dtype=float)
    except (TypeError, ValueError) as error:
        raise ValueError(f"levels: must be numbers (fault sizes, SI), got {levels!r}") from error
    if levels.ndim != 1 or len(levels) < 2:
        raise ValueError(f"levels has shape {levels.shape}: must be one-dimensional with at least 2 fault sizes "
                         "(the baseline, 0, and one fault level)")
    if not np.isfinite(levels).all() or levels[0] != 0.0 or (np.diff(levels) <= 0.0).any():
        raise ValueError(f"levels = {levels.tolist()}: must be finite and strictly increasing from 0 (the fault size "
                         "of the unit's baseline tests)")
    try:
        values = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as error:
        raise ValueError("values: must be numbers indexed [level, unit, repeat] (NaN: a failed run)") from error
    if values.ndim != 3 or values.shape[0] != len(levels) or 0 in values.shape:
        raise ValueError(f"values has shape {values.shape}: must be (level, unit, repeat) = ({len(levels)}, U, R) "
                         "with U >= 1 units and R >= 1 repeats (NaN: a failed run)")
    return levels, values


def _cells(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ok repeats, mean and sum of squared deviations from the mean of each (level, unit) cell."""
    ok = np.isfinite(values)
    n = ok.sum(axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(ok, values, 0.0).sum(axis=2) / n
    squares = np.where(ok, (values - mean[:, :, None]) ** 2, 0.0).sum(axis=2)
    return n, mean, squares


def _detection(n: np.ndarray, mean: np.ndarray, squares: np.ndarray, false_alarm_rate: float) -> dict:
    """The rule on cell statistics of shape (..., level, unit): pooled scatters, thresholds, detection probabilities.

    Leading axes are bootstrap replicates; every unit given is used.
    """
    dof = (n - 1).sum(axis=-1)
    scatter = np.sqrt(squares.sum(axis=-1) / dof)
    baseline_n, baseline_mean = n[..., 0, :], mean[..., 0, :]
    margin = (stats.t.ppf(1.0 - false_alarm_rate, dof[..., :1]) * scatter[..., :1]
              * np.sqrt(1.0 + 1.0 / baseline_n))
    excess = np.abs(mean - baseline_mean[..., None, :]) - margin[..., None, :]  # threshold on the side of the shift
    # a level without test-to-test scatter (a feature fixed by the unit alone) flags every test or none
    deterministic = np.where(np.isnan(excess), math.nan, np.where(excess > 0.0, math.inf, -math.inf))
    with np.errstate(invalid="ignore", divide="ignore"):
        probability = stats.norm.cdf(np.where(scatter[..., :, None] > 0.0, excess / scatter[..., :, None],
                                              deterministic))
    return {"dof": dof, "scatter": scatter, "low": baseline_mean - margin, "high": baseline_mean + margin,
            "probability": probability}


def _first_detected(levels: np.ndarray, probability: np.ndarray, power: float) -> tuple[np.ndarray, np.ndarray]:
    """The bracket of :func:`campaigns.statistics.detection.minimum_detectable` for probabilities of shape (...,
    level, unit): the last level not detected and the first level detected (``levels[-1]`` and ``inf`` when none is)."""
    reached = probability >= power
    first = np.argmax(reached, axis=-2)
    any_reached = reached.any(axis=-2)
    lower = np.where(any_reached, levels[np.maximum(first - 1, 0)], levels[-1])
    upper = np.where(any_reached, levels[first], math.inf)
    return lower, upper


def _rank(n: int, quantile: float) -> int:
    """0-based index of the ``inverted_cdf`` quantile among ``n`` sorted values (no interpolation: ``inf`` stays)."""
    return max(math.ceil(quantile * n) - 1, 0)


def unit_detection(levels, values, *, false_alarm_rate: float = FALSE_ALARM_RATE, power: float = POWER,
                   min_repeats: int = MIN_REPEATS) -> dict:
    """The within-unit detection rule applied to each unit: its threshold, detection probabilities and minimum.

    Parameters
    ----------
    levels : array_like, shape (L,)
        Fault sizes [SI], strictly increasing from 0 (the baseline); at least 2.
    values : array_like, shape (L, U, R)
        Feature of each test ``[level, unit, repeat]``; non-finite: a failed run, excluded.
    false_alarm_rate, power : float
        Each unit's threshold flags ``false_alarm_rate`` of its baseline tests (the prediction bound of the module
        docstring); its minimum detectable growth is where ``power`` of its tests are flagged.
    min_repeats : int, default :data:`MIN_REPEATS`
        Ok repeats a unit needs at every level to be used (at least 3: the check of the shared scatter).

    Returns
    -------
    dict
        ``n_used``, ``n_excluded`` (L, U); ``used`` (U,) bool; ``scatter`` and ``dof`` (L,), the pooled test-to-test
        standard deviation [feature units] and its degrees of freedom; ``threshold_low``, ``threshold_high`` (U,);
        ``probability`` (L, U); ``estimate`` (U,) interpolated minimum detectable growth (``inf``: not reached) and
        ``bracket`` (U, 2) the sweep levels around it, from
        :func:`campaigns.statistics.detection.minimum_detectable`;
        ``equal_scatter_pvalue`` and ``normality_pvalue`` (L,), the checks of the shared distribution. Unused units
        and levels without a check get NaN.
    """
    levels, values = _checked(levels, values)
    if min_repeats < MIN_REPEATS:
        raise ValueError(f"min_repeats = {min_repeats}: must be at least {MIN_REPEATS} (the Brown-Forsythe check of "
                         "the shared scatter needs 3 repeats per unit)")
    n_levels, n_units, _ = values.shape
    n, mean, squares = _cells(values)
    used = (n >= min_repeats).all(axis=0)
    out = {
        "n_used": n, "n_excluded": values.shape[2] - n, "used": used,
        "scatter": np.full(n_levels, math.nan), "dof": np.zeros(n_levels, dtype=np.int64),
        "threshold_low": np.full(n_units, math.nan), "threshold_high": np.full(n_units, math.nan),
        "probability": np.full((n_levels, n_units), math.nan),
        "estimate": np.full(n_units, math.nan), "bracket": np.full((n_units, 2), math.nan),
        "equal_scatter_pvalue": np.full(n_levels, math.nan), "normality_pvalue": np.full(n_levels, math.nan),
    }
    if not used.any():
        return out
    rule = _detection(n[:, used], mean[:, used], squares[:, used], false_alarm_rate)
    out["scatter"], out["dof"] = rule["scatter"], rule["dof"]
    out["threshold_low"][used], out["threshold_high"][used] = rule["low"], rule["high"]
    out["probability"][:, used] = rule["probability"]
    for u in np.flatnonzero(used):
        estimate, lower, upper = minimum_detectable(levels, out["probability"][:, u], power)
        out["estimate"][u] = estimate if math.isfinite(estimate) else math.inf
        out["bracket"][u] = lower, upper
    if used.sum() >= 2:
        for level in np.flatnonzero(out["scatter"] > 0.0):  # without scatter there is nothing to check
            groups = [row[np.isfinite(row)] for row in values[level, used]]
            out["equal_scatter_pvalue"][level] = stats.levene(*groups, center="median").pvalue
            # residuals scaled to the scatter of one test (n / (n - 1): each unit's mean removed)
            residuals = np.concatenate([(g - g.mean()) * math.sqrt(len(g) / (len(g) - 1)) for g in groups])
            if len(residuals) >= 8:  # the smallest sample normaltest accepts
                out["normality_pvalue"][level] = stats.normaltest(residuals).pvalue
    return out


def extrapolated_detectable(values, growth: float, *, false_alarm_rate: float = FALSE_ALARM_RATE,
                            power: float = POWER, min_repeats: int = MIN_REPEATS) -> np.ndarray:
    """Each unit's detectable growth under the rule of :func:`unit_detection`, extrapolated linearly from one level.

    With the baseline and one growth level only (a screening campaign, :mod:`campaigns.workflows.procedure_search`), a
    unit whose feature moved by ``s`` at ``growth`` is taken to move by ``s g / growth`` at ``g``; the rule flags a test
    with probability ``power`` once the shift exceeds the unit's threshold margin by ``z_power`` scatters, so

        g_u = growth (margin_u + z_power sigma) / |s_u|

    with the pooled scatters and margins of the rule. A ranking statistic (the feature need not be linear in the
    fault); verdicts come from the full sweep.

    Parameters
    ----------
    values : array_like, shape (2, U, R)
        The feature at the baseline and at ``growth``; non-finite: a failed run.
    growth : float
        The fault growth of the second level [SI], > 0.

    Returns
    -------
    numpy.ndarray, shape (U,)
        ``inf`` where the unit did not move; NaN for a unit with fewer than ``min_repeats`` ok repeats at a level.
    """
    values = np.asarray(values, dtype=float)
    if values.ndim != 3 or values.shape[0] != 2 or not growth > 0:
        raise ValueError(f"values must have shape (2, units, repeats) and growth be > 0, got {values.shape} and "
                         f"{growth!r}")
    n, mean, squares = _cells(values)
    used = (n >= min_repeats).all(axis=0)
    out = np.full(values.shape[1], math.nan)
    if not used.any():
        return out
    rule = _detection(n[:, used], mean[:, used], squares[:, used], false_alarm_rate)
    margin = (rule["high"] - rule["low"]) / 2.0
    shift = np.abs(mean[1, used] - mean[0, used])
    with np.errstate(divide="ignore"):
        out[used] = np.where(shift > 0.0, growth * (margin + stats.norm.ppf(power) * rule["scatter"][1]) / shift,
                             math.inf)
    return out


def population_detectable(levels, values, *, quantiles=UNIT_QUANTILES, false_alarm_rate: float = FALSE_ALARM_RATE,
                          power: float = POWER, n_boot: int = 1000, confidence: float = CONFIDENCE,
                          min_units: int | None = None, min_repeats: int = MIN_REPEATS, seed=None,
                          requirement: float = BACKLASH_REQUIREMENT) -> dict:
    """Quantiles of the per-unit minimum detectable growth over units, with bounds, and the verdict.

    Parameters
    ----------
    levels, values, false_alarm_rate, power, min_repeats
        As in :func:`unit_detection`.
    quantiles : sequence of float, default :data:`UNIT_QUANTILES`
        Quantiles of the unit population reported; the verdict is for :data:`DESIGN_REVIEW_QUANTILE`, which must be
        among them.
    n_boot, confidence, seed
        Bootstrap over units (module docstring): bounds at ``(1 -/+ confidence) / 2`` of the replicates, widened to
        the order-statistic bounds of the quantile at ``confidence`` and to the bracket of the estimate.
    min_units : int, optional
        Used units needed (default :func:`unit_floor` of ``quantiles`` and ``confidence``).
    requirement : float
        Requirement on the fault size [SI] (Table 9.3's 1 µm backlash by default).

    Returns
    -------
    dict
        ``units`` (:func:`unit_detection`), ``n_units_used``, ``min_units``, ``quantiles``, and per quantile (arrays
        over ``quantiles``): ``estimate`` (interpolated; NaN when not reached), ``printed`` (NaN unless resolved,
        :func:`campaigns.statistics.detection.printed_estimate`), ``bracket`` and ``bounds`` (Q, 2),
        ``resolution`` (:func:`campaigns.statistics.detection.sweep_resolution`, ``"insufficient_data"`` below
        the floor); ``verdict``.
    """
    levels, values = _checked(levels, values)
    quantiles = tuple(float(q) for q in quantiles)
    if DESIGN_REVIEW_QUANTILE not in quantiles or not all(0.0 < q < 1.0 for q in quantiles):
        raise ValueError(f"quantiles = {quantiles}: must lie strictly between 0 and 1 and include the design-review "
                         f"quantile {DESIGN_REVIEW_QUANTILE}")
    if min_units is None:
        min_units = unit_floor(quantiles, confidence)
    units = unit_detection(levels, values, false_alarm_rate=false_alarm_rate, power=power, min_repeats=min_repeats)
    used = np.flatnonzero(units["used"])
    count = len(quantiles)
    out = {"units": units, "n_units_used": len(used), "min_units": min_units, "quantiles": np.array(quantiles),
           "estimate": np.full(count, math.nan), "printed": np.full(count, math.nan),
           "bracket": np.full((count, 2), math.nan), "bounds": np.full((count, 2), math.nan),
           "resolution": ["insufficient_data"] * count, "verdict": "insufficient data"}
    if len(used) < max(min_units, 2):
        return out
    n, mean, squares = _cells(values[:, used])
    resample = np.random.default_rng(seed).integers(0, len(used), (n_boot, len(used)))
    boot = _detection(n[:, resample].transpose(1, 0, 2), mean[:, resample].transpose(1, 0, 2),
                      squares[:, resample].transpose(1, 0, 2), false_alarm_rate)
    boot_lower, boot_upper = _first_detected(levels, boot["probability"], power)  # (n_boot, units)
    boot_lower, boot_upper = np.sort(boot_lower, axis=1), np.sort(boot_upper, axis=1)
    estimates, brackets = units["estimate"][used], units["bracket"][used]
    order = np.argsort(estimates, kind="stable")
    lower_sorted, upper_sorted = np.sort(brackets[:, 0]), np.sort(brackets[:, 1])
    alpha = 0.5 * (1.0 - confidence)
    for i, q in enumerate(quantiles):
        rank = _rank(len(used), q)
        unit = order[rank]
        estimate = estimates[unit] if math.isfinite(estimates[unit]) else math.nan
        bracket = brackets[unit]
        upper_rank = quantile_bound_rank(len(used), q, confidence)  # 1-based; None: no order statistic bounds it
        lower_rank = quantile_bound_rank(len(used), 1.0 - q, confidence)
        bounds = (
            min(float(np.quantile(boot_lower[:, rank], alpha, method="inverted_cdf")), bracket[0],
                lower_sorted[len(used) - lower_rank] if lower_rank is not None else levels[0]),
            max(float(np.quantile(boot_upper[:, rank], 1.0 - alpha, method="inverted_cdf")), bracket[1],
                upper_sorted[upper_rank - 1] if upper_rank is not None else math.inf),
        )
        resolution = sweep_resolution(levels, estimate, bounds)
        out["estimate"][i], out["bracket"][i], out["bounds"][i] = estimate, bracket, bounds
        out["resolution"][i] = resolution
        out["printed"][i] = printed_estimate(estimate, bounds) if resolution == "resolved" else math.nan
    out["verdict"] = requirement_verdict(*out["bounds"][quantiles.index(DESIGN_REVIEW_QUANTILE)], requirement)
    return out


def within_unit_dataset(levels, values, *, feature_units: str = "1", condition: str = "backlash",
                        false_alarm_rate: float = FALSE_ALARM_RATE, power: float = POWER, n_boot: int = 1000,
                        confidence: float = CONFIDENCE, min_units: int | None = None,
                        min_repeats: int = MIN_REPEATS, seed=None, requirement: float = BACKLASH_REQUIREMENT,
                        requirement_source: str = REQUIREMENT_SOURCE) -> xr.Dataset:
    """Everything of :func:`population_detectable` as a dataset with CF attributes, for analysis.nc.

    Parameters
    ----------
    levels, values, false_alarm_rate, power, n_boot, confidence, min_units, min_repeats, seed, requirement
        As in :func:`population_detectable`.
    feature_units : str
        Units of the feature (of the scatters and thresholds).
    condition : str
        The swept condition (:data:`campaigns.analysis.vocabulary.SWEEP_QUANTITIES`): names the fault quantity
        ``<q>``.
    requirement_source : str
        Where the requirement comes from (stored, and named in the sentence).

    Returns
    -------
    xarray.Dataset
        On dimensions ``level``, ``unit``, ``unit_quantile`` and ``bound``: ``within_unit_<q>(level)``,
        ``within_unit_n_used`` / ``within_unit_n_excluded(level, unit)``, ``within_unit_scatter`` /
        ``within_unit_scatter_dof`` / ``within_unit_equal_scatter_pvalue`` / ``within_unit_normality_pvalue(level)``,
        ``within_unit_threshold_low`` / ``_high(unit)``, ``within_unit_detection_probability(level, unit)``,
        ``within_unit_detectable_bracket(unit, bound)``, ``within_unit_minimum_detectable_<q>(unit_quantile)`` (NaN
        unless resolved), ``within_unit_minimum_detectable_status(unit_quantile)``,
        ``within_unit_minimum_detectable_bracket`` / ``within_unit_minimum_detectable_<q>_ci(unit_quantile, bound)``,
        ``within_unit_n_units_used``, ``within_unit_requirement_verdict`` and ``within_unit_requirement_statement``
        (:func:`within_unit_statement` of this dataset).
    """
    quantity, unit, _, _ = SWEEP_QUANTITIES[condition]
    stem = quantity.replace(" ", "_")
    found = population_detectable(levels, values, false_alarm_rate=false_alarm_rate, power=power, n_boot=n_boot,
                                  confidence=confidence, min_units=min_units, min_repeats=min_repeats, seed=seed,
                                  requirement=requirement)
    units = found["units"]
    levels = np.asarray(levels, dtype=float)
    probability_name = f"{quantity} growth detected with probability {power:g} at false-alarm rate {false_alarm_rate:g}"
    dimensionless = {"units": "1"}
    ds = xr.Dataset(
        {
            f"within_unit_{stem}": ("level", levels, {"units": unit, "long_name": f"{quantity} of the level, from "
                                                                                  "the unit's baseline"}),
            "within_unit_n_used": (("level", "unit"), units["n_used"].astype(np.int32), dimensionless | {
                "long_name": "ok repeats of the unit at the level"}),
            "within_unit_n_excluded": (("level", "unit"), units["n_excluded"].astype(np.int32), dimensionless | {
                "long_name": "failed (non-finite) repeats of the unit at the level, excluded"}),
            "within_unit_scatter": ("level", units["scatter"], {
                "units": feature_units,
                "long_name": "test-to-test standard deviation at the level, pooled over the used units after "
                             "removing each unit's own mean"}),
            "within_unit_scatter_dof": ("level", units["dof"].astype(np.int32), dimensionless | {
                "long_name": "degrees of freedom of within_unit_scatter (sum over used units of repeats - 1)"}),
            "within_unit_equal_scatter_pvalue": ("level", units["equal_scatter_pvalue"], dimensionless | {
                "long_name": "Brown-Forsythe test of equal test-to-test variances across units at the level "
                             "(scipy.stats.levene, center=median): p-value"}),
            "within_unit_normality_pvalue": ("level", units["normality_pvalue"], dimensionless | {
                "long_name": "D'Agostino-Pearson test of normality of the pooled test-to-test residuals at the "
                             "level (scipy.stats.normaltest): p-value"}),
            "within_unit_threshold_low": ("unit", units["threshold_low"], {
                "units": feature_units,
                "long_name": f"lower detection threshold of the unit at false-alarm rate {false_alarm_rate:g}: its "
                             "baseline mean minus the prediction bound of one test from the pooled scatter"}),
            "within_unit_threshold_high": ("unit", units["threshold_high"], {
                "units": feature_units,
                "long_name": f"upper detection threshold of the unit at false-alarm rate {false_alarm_rate:g}: its "
                             "baseline mean plus the prediction bound of one test from the pooled scatter"}),
            "within_unit_detection_probability": (("level", "unit"), units["probability"], dimensionless | {
                "long_name": f"probability that a test of the unit at the level is flagged by the unit's threshold "
                             f"(false-alarm rate {false_alarm_rate:g}; NaN: unit not used)"}),
            "within_unit_detectable_bracket": (("unit", "bound"), units["bracket"], {
                "units": unit,
                "long_name": f"sweep levels bracketing the unit's smallest {probability_name} (lower: not "
                             "detected; upper: detected, inf: never)"}),
            f"within_unit_minimum_detectable_{stem}": ("unit_quantile", np.where(
                [r == "resolved" for r in found["resolution"]], found["estimate"], math.nan), {
                "units": unit,
                "long_name": f"smallest {probability_name}, of the unit at the quantile of the unit population, "
                             "interpolated along the sweep, only where the sweep resolves it, else NaN: read "
                             "within_unit_minimum_detectable_bracket",
                "requirement": requirement, "requirement_source": requirement_source}),
            "within_unit_minimum_detectable_status": ("unit_quantile", np.array(
                [RESOLUTIONS.index(r) for r in found["resolution"]], dtype=np.int8), {
                "long_name": "how far the sweep resolves the quantile unit's minimum detectable level",
                "flag_values": np.arange(len(RESOLUTIONS), dtype=np.int8), "flag_meanings": " ".join(RESOLUTIONS)}),
            "within_unit_minimum_detectable_bracket": (("unit_quantile", "bound"), found["bracket"], {
                "units": unit, "long_name": "sweep levels bracketing the quantile unit's minimum detectable level "
                                            "(inf: never detected)"}),
            f"within_unit_minimum_detectable_{stem}_ci": (("unit_quantile", "bound"), found["bounds"], {
                "units": unit,
                "long_name": f"bounds of the quantile unit's minimum detectable {quantity} growth, bootstrap over "
                             "units and order statistics of the units: lower = a sweep level not detected, upper = "
                             "a sweep level detected (inf: not reached)",
                "confidence": confidence, "n_boot": n_boot}),
            "within_unit_n_units_used": ((), np.int32(found["n_units_used"]), dimensionless | {
                "long_name": f"units with at least {min_repeats} ok repeats at every level",
                "min_units": found["min_units"]}),
            "within_unit_requirement_verdict": ((), found["verdict"], {
                "long_name": f"verdict on the requirement for the {DESIGN_REVIEW_QUANTILE * 100:g}th-percentile "
                             "unit: met / not met / undetermined / insufficient data"}),
        },
        coords={  # 32-bit integers: CF 1.8 (Sec. 2.2) has no 64-bit type
            "level": ("level", np.arange(len(levels), dtype=np.int32), {
                "long_name": "index of the fault level (0: baseline)"}),
            "unit": ("unit", np.arange(units["used"].size, dtype=np.int32), {"long_name": "index of the unit"}),
            "unit_quantile": ("unit_quantile", found["quantiles"], {
                "units": "1", "long_name": "quantile of the unit population"}),
            "bound": ("bound", np.array(["lower", "upper"], dtype=object)),
        },
        attrs={"within_unit_condition": condition, "within_unit_false_alarm_rate": false_alarm_rate,
               "within_unit_power": power, "within_unit_min_repeats": min_repeats},
    )
    ds["within_unit_requirement_statement"] = ((), within_unit_statement(ds), {
        "long_name": "the within-unit verdict with the estimates, their bounds, the sample sizes and the check of "
                     "the shared scatter, in one sentence"})
    return ds


def within_unit_statement(ds: xr.Dataset) -> str:
    """The sentence stating the within-unit verdict, from the numbers of :func:`within_unit_dataset` only.

    A value is printed only where the sweep resolves it (rounded to its bounds,
    :func:`campaigns.statistics.detection.printed_estimate`); otherwise the sweep levels around it are, as in
    :func:`campaigns.analysis.observability.requirement_statement`.
    """
    condition = ds.attrs["within_unit_condition"]
    quantity, unit, scale, shown = SWEEP_QUANTITIES[condition]
    stem = quantity.replace(" ", "_")
    estimate = ds[f"within_unit_minimum_detectable_{stem}"]
    requirement, source = estimate.attrs["requirement"], estimate.attrs["requirement_source"]
    source = source.removeprefix("Bertolino (2020) ").split(":")[0]
    against = f"against the {requirement * scale:.3g} {shown} requirement of {source}"
    used, min_units = int(ds["within_unit_n_units_used"]), int(ds["within_unit_n_units_used"].attrs["min_units"])
    min_repeats = int(ds.attrs["within_unit_min_repeats"])
    verdict = str(ds["within_unit_requirement_verdict"].values)

    def fmt(value: float) -> str:
        return f"{value * scale:.3g} {shown}"

    if verdict == "insufficient data":
        return (f"insufficient data: {used} of {ds.sizes['unit']} units have at least {min_repeats} ok repeats at "
                f"every level; at least {min_units} are needed (with fewer, not even the largest unit bounds the "
                f"{DESIGN_REVIEW_QUANTILE * 100:g}th-percentile unit from above with "
                f"{float(ds[f'within_unit_minimum_detectable_{stem}_ci'].attrs['confidence']) * 100:g} % "
                f"confidence), so no within-unit minimum detectable {quantity} growth is estimated {against}")

    def figure(q: float) -> str:
        row = {"unit_quantile": q}
        status = RESOLUTIONS[int(ds["within_unit_minimum_detectable_status"].sel(row))]
        lower, upper = ds[f"within_unit_minimum_detectable_{stem}_ci"].sel(row).values
        bracket = ds["within_unit_minimum_detectable_bracket"].sel(row).values
        if status == "resolved":
            value = fmt(printed_estimate(float(estimate.sel(row)), (lower, upper)))
        elif status == "between_adjacent_levels":
            value = f"between the adjacent sweep levels {fmt(bracket[0])} and {fmt(bracket[1])}"
        else:
            value = f"above {fmt(bracket[0])}, the largest sweep level"
        upper_text = f"at most {fmt(upper)}" if math.isfinite(upper) else "possibly beyond the sweep"
        return f"{value} (bounds: above {fmt(lower)}, {upper_text})"

    name = {0.5: "the median unit"}
    parts = [f"{name.get(float(q), f'the {float(q) * 100:g}th-percentile unit')} {figure(float(q))}"
             for q in ds["unit_quantile"].values if float(q) != DESIGN_REVIEW_QUANTILE]
    n_used = ds["within_unit_n_used"]
    repeats = n_used.values[:, (n_used >= min_repeats).all("level").values]
    counts = f"{repeats.min()}" if repeats.min() == repeats.max() else f"{repeats.min()}–{repeats.max()}"
    p_scatter = ds["within_unit_equal_scatter_pvalue"].values
    p_normal = ds["within_unit_normality_pvalue"].values
    limit = CHECK_SIGNIFICANCE / ds.sizes["level"]
    rejected = [f"level {fmt(float(level))}" for level, a, b in zip(
        ds[f"within_unit_{stem}"].values, p_scatter, p_normal, strict=True) if min(a, b) < limit]
    check = (f"rejected at {', '.join(rejected)}, so the units' thresholds are not those of their own scatter"
             if rejected else "not rejected")
    if np.isnan(p_scatter).all() and np.isnan(p_normal).all():
        return (f"{verdict}: within-unit minimum detectable {quantity} growth of the "
                f"{DESIGN_REVIEW_QUANTILE * 100:g}th-percentile unit {figure(DESIGN_REVIEW_QUANTILE)}"
                f"{'; ' + '; '.join(parts) if parts else ''} ({used} units, {counts} ok repeats per unit and level, "
                f"{ds.sizes['level']} levels) {against}; the feature does not vary from test to test (no scatter "
                "at any level): each unit's tests give one value per level, so every growth that moves it is "
                "detected and the figure is the first such sweep level")
    return (
        f"{verdict}: within-unit minimum detectable {quantity} growth of the "
        f"{DESIGN_REVIEW_QUANTILE * 100:g}th-percentile unit {figure(DESIGN_REVIEW_QUANTILE)}"
        f"{'; ' + '; '.join(parts) if parts else ''} "
        f"({float(ds[f'within_unit_minimum_detectable_{stem}_ci'].attrs['confidence']) * 100:g} % bounds over "
        f"{used} units, {counts} ok repeats per unit and level, {ds.sizes['level']} levels; each unit's threshold "
        f"from its own baseline at false-alarm rate {float(ds.attrs['within_unit_false_alarm_rate']) * 100:g} % "
        f"with the test-to-test scatter pooled over units, detection at "
        f"{float(ds.attrs['within_unit_power']) * 100:g} %) {against}; the shared test-to-test distribution is "
        f"{check} (Brown-Forsythe and D'Agostino-Pearson smallest p = {np.nanmin(p_scatter):.2g} and "
        f"{np.nanmin(p_normal):.2g}, at {CHECK_SIGNIFICANCE:g} over {ds.sizes['level']} levels)"
    )


def unit_values(results: xr.Dataset, feature: str, datasets: list[str], condition: str = "backlash",
                reference: str | None = None) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """A within-unit campaign's ``values[level, unit, repeat]`` of ``feature`` along its observability sweep.

    Parameters
    ----------
    results : xarray.Dataset
        A campaign's ``results.nc`` with the ``unit`` and ``repeat`` coordinates along ``run`` (the spec's
        ``[units]``).
    feature : str
    datasets, condition, reference
        The sweep (``observability`` of the spec; :func:`campaigns.analysis.vocabulary.sweep_levels`).

    Returns
    -------
    tuple
        The fault sizes [SI] in increasing order (the reference first), the values (NaN: a run not ok or a
        non-finite feature, as the analysis excludes them) and the data sets in the order of the levels.
    """
    sizes, _ = sweep_levels(results, datasets, condition, reference)
    order = np.argsort(sizes, kind="stable")
    unit, repeat = results["unit"].values, results["repeat"].values
    values = np.full((len(datasets), int(unit.max()) + 1, int(repeat.max()) + 1), math.nan)
    used = ok_runs(results, feature)
    for level, d in enumerate(order):
        row = results[feature].sel(dataset=datasets[d]).values
        values[level, unit, repeat] = np.where(used.sel(dataset=datasets[d]).values, row, math.nan)
    return sizes[order], values, [datasets[d] for d in order]


def within_unit_analysis(results: xr.Dataset, settings: AnalysisSettings) -> xr.Dataset:
    """:func:`within_unit_dataset` of every feature of a within-unit campaign, along a ``feature`` dimension; an empty
    dataset for any other campaign.

    The bootstrap of feature ``f`` draws from ``SeedSequence(seed, spawn_key=(WITHIN_UNIT_STREAM, f))``; the
    detection settings, ``n_boot`` and ``confidence`` are the analysis's.

    Returns
    -------
    xarray.Dataset
        The variables of :func:`within_unit_dataset` with a ``feature`` dimension (the fault levels once, with the
        ``level_dataset`` coordinate naming each level's data set), and its settings as global attributes.
    """
    spec = stored_spec(results)
    if not is_within_unit(spec):
        return xr.Dataset()
    observability = spec["observability"]
    features = features_of(results)
    condition = observability.get("condition", "backlash")
    stem = SWEEP_QUANTITIES[condition][0].replace(" ", "_")
    requirement, source = requirement_of(observability)
    per_feature = []
    for f, feature in enumerate(features):
        levels, values, names = unit_values(results, feature, observability["sweep"], condition,
                                            observability.get("reference"))
        per_feature.append(within_unit_dataset(
            levels, values, feature_units=str(results[feature].attrs.get("units", "1")), condition=condition,
            seed=np.random.SeedSequence(settings.seed, spawn_key=(WITHIN_UNIT_STREAM, f)), requirement=requirement,
            requirement_source=source, false_alarm_rate=settings.false_alarm_rate, power=settings.power,
            n_boot=settings.n_boot, confidence=settings.confidence))
    levels_name = f"within_unit_{stem}"
    combined = xr.concat([ds.drop_vars(levels_name) for ds in per_feature], dim="feature",
                         combine_attrs="override")
    combined[levels_name] = per_feature[0][levels_name]
    in_feature_units = feature_units([str(results[f].attrs.get("units", "1")) for f in features])
    for name in ("within_unit_scatter", "within_unit_threshold_low", "within_unit_threshold_high"):
        combined[name].attrs.pop("units")
        combined[name].attrs.update(in_feature_units)
    return combined.assign_coords(
        feature=("feature", np.array(features, dtype=object)),
        level_dataset=("level", np.array(names, dtype=object), {"long_name": "data set of the fault level"}))
