"""The detection requirement along an observability sweep, as the analysis states it: the requirement, the swept
fault quantity and its levels, and the answer in a picture; one view of the analysis per sweep (:func:`sweep_views`).

:func:`detection_answer` needs ``analysis.nc`` alone, so page 1 of the report (:mod:`reports.sections.executive`) and
the service's campaign page (:mod:`app.service.web`) draw the same figure; the Observability section reads the sweep
the same way.
"""

from __future__ import annotations

import math

import numpy as np

from campaigns.analysis.vocabulary import BACKLASH_REQUIREMENT, SWEEP_QUANTITIES, marked_features
from reports.figures import Points, detection, level_axis, literal
from reports.phrases import decision
from reports.units import axis_label, display_scale, number


def sweep_views(analysis) -> list[tuple[str, object]]:
    """Each fault sweep of the analysis as ``(key, view)``: the view reads as the analysis of a spec with that sweep
    alone, so every function here (and page 1, the Observability section, the service) reads any sweep the same
    way. The first sweep's view is the analysis itself (key ``""``); a further sweep's (key ``"_preload"``,
    :func:`campaigns.analysis.vocabulary.sweep_key`) has its variables and sweep dimension under the plain names and
    its condition and requirement in the global attributes, where the first sweep's stand."""
    views = [("", analysis)]
    for name in analysis.data_vars:
        if not (name.startswith("requirement_verdict_") and "sweep" in analysis[name].attrs):
            continue
        key = name.removeprefix("requirement_verdict")
        own = [v for v in analysis.data_vars if v.endswith(key) and analysis[v].attrs.get("sweep") is not None]
        first = [v for v in analysis.data_vars if "sweep_point" in analysis[v].dims or v in
                 {o.removesuffix(key) for o in own}]
        view = analysis.drop_vars([*first, *(["sweep_point"] if "sweep_point" in analysis.coords else [])])
        view = view.rename({**{v: v.removesuffix(key) for v in own}, f"sweep_point{key}": "sweep_point"})
        attrs = analysis[name].attrs
        view.attrs = {**analysis.attrs, **{k: attrs[k] for k in ("observability_condition", "requirement",
                                                                  "requirement_units", "requirement_source")}}
        views.append((key, view))
    return views


def backlash_requirement(analysis) -> tuple[float, str]:
    """The requirement the observability verdict is about, as the analysis states it."""
    if "requirement" in analysis.attrs:
        return float(analysis.attrs["requirement"]), str(analysis.attrs.get("requirement_source", ""))
    if "minimum_detectable_backlash" in analysis:
        attrs = analysis["minimum_detectable_backlash"].attrs
        return float(attrs.get("requirement", BACKLASH_REQUIREMENT)), str(attrs.get("requirement_source", "Table 9.3"))
    return BACKLASH_REQUIREMENT, "Table 9.3"


def swept(analysis) -> tuple[str, str, float, str]:
    """The swept fault quantity as the analysis names it (``observability_condition``, a backlash when it names
    none): its name, SI unit, display scale and display unit (``("backlash", "m", 1e6, "µm")``)."""
    condition = str(analysis.attrs.get("observability_condition", "backlash"))
    return SWEEP_QUANTITIES.get(condition, SWEEP_QUANTITIES["backlash"])


def minimum_detectable(quantity_name: str) -> str:
    """The analysis's variable of the minimum detectable fault size (``minimum_detectable_preload_loss``); its 95 %
    bounds are the same name with ``_ci``."""
    return f"minimum_detectable_{quantity_name.replace(' ', '_')}"


def sweep_quantity(analysis) -> tuple[str, np.ndarray, float, str]:
    """The swept fault quantity, its levels [SI], and its display scale and unit (µm for a backlash, N for a preload
    loss), as the analysis names them."""
    quantity_name, _, scale, shown = swept(analysis)
    name = f"sweep_{quantity_name.replace(' ', '_')}"
    return quantity_name, np.asarray(analysis[name].values, dtype=float), scale, shown


def _pairs(analysis) -> list[tuple[str, str | None]]:
    """Each measured feature the sweep is about (:func:`campaigns.analysis.vocabulary.marked_features`) with its
    ideal-sensor counterpart (``<feature>_true``) when the sweep is about that too."""
    features = [str(f) for f in analysis["feature"].values]
    marked = marked_features(analysis)
    return [(f, f + "_true" if f + "_true" in marked else None)
            for f in marked if not (f.endswith("_true") and f.removesuffix("_true") in features)]


def _decision_label(analysis, feature: str, scale: float, shown: str, quantity_name: str) -> str:
    """``backlash_feature: NO-GO, 1–2 µm (95 % bounds)``: the analysis's verdict and the bounds of the minimum
    detectable size, in the figure's legend (short: the legend has two columns on the page's width)."""
    verdict = str(analysis["requirement_verdict"].sel(feature=feature).item())
    name = minimum_detectable(quantity_name) + "_ci"
    lower, upper = ((float(v) for v in analysis[name].sel(feature=feature).values) if name in analysis
                    else (math.nan, math.nan))
    decided = decision(verdict)
    if not (math.isfinite(lower) or math.isfinite(upper)):
        return f"{feature}: {decided}"
    high = f"{number(upper * scale)} {shown}" if math.isfinite(upper) else "beyond the sweep"
    return f"{feature}: {decided}, {number(lower * scale)}–{high} (95 % bounds)"


def detection_answer(analysis) -> tuple[bytes, str] | None:
    """The answer to the detection requirement in a picture, with its caption: ``(png, caption)``, or None when the
    analysis has no sweep (or predates the verdict).

    Detection probability against fault size, each measured feature's points with their 95 % intervals per sweep level
    (its ideal-sensor reading beside it, open squares), the power target, the requirement, and each feature's verdict
    with the 95 % bounds of its minimum detectable size (a bar above the points). Below the detection floor the
    detection probabilities are withheld, and the picture shows each level's feature mean with its t interval
    instead. Page 1 of the report draws it, and so can the service's campaign page: it needs ``analysis.nc`` alone.
    """
    if "sweep_point" not in analysis.dims or "requirement_verdict" not in analysis:
        return None
    quantity_name, levels, scale, shown = sweep_quantity(analysis)
    requirement, source = backlash_requirement(analysis)
    power = float(analysis.attrs.get("detection_power", 0.95))
    fa = float(analysis.attrs.get("false_alarm_rate", 0.05))
    sweep = [str(s) for s in analysis["sweep_point"].values]
    pairs = _pairs(analysis)
    if not sweep or not pairs:
        return None
    n = min(int(analysis["n_used"].sel(dataset=d, feature=f)) for d in sweep for f, _ in pairs)
    x = levels * scale
    units = (str(analysis["feature_units"].sel(feature=pairs[0][0]).item()) if "feature_units" in analysis.coords
             else "m")
    factor, unit = display_scale(units, analysis["feature_mean"].sel(feature=[f for f, _ in pairs]).values)
    probability = analysis["sweep_detection_probability"]
    detected = bool(np.isfinite(probability.values).any())
    series = []
    for k, (feature, true) in enumerate(pairs):
        for name, filled in ((feature, True), (true, False)):
            if name is None:
                continue
            label = name if filled else f"{name} (ideal sensors)"
            if detected:
                y = probability.sel(feature=name).values
                ci = (analysis["sweep_detection_probability_ci"].sel(feature=name).values
                      if "sweep_detection_probability_ci" in analysis else np.full((len(sweep), 2), math.nan))
                series.append(Points(label, x, y, ci[:, 0], ci[:, 1], f"C{k}", filled))
            elif "feature_mean_ci" in analysis:
                cell = analysis.sel(feature=name, dataset=sweep)
                series.append(Points(label, x, cell["feature_mean"].values * factor,
                                     *(cell["feature_mean_ci"].values.T * factor), f"C{k}", filled))
    if not series:
        return None
    where = ("; a logarithmic axis cannot show the reference level 0, which is left out" if level_axis(x) == "log"
             and (x == 0).any() else "")
    requirement_line = (f"requirement {number(requirement * scale)} {shown} ({literal(source.split(':')[0])})",
                        requirement * scale)
    if detected:
        ci = minimum_detectable(quantity_name) + "_ci"
        bounds = [(_decision_label(analysis, f, scale, shown, quantity_name),
                   *((float(v) * scale for v in analysis[ci].sel(feature=f).values) if ci in analysis
                     else (math.nan, math.nan)), f"C{k}") for k, (f, _) in enumerate(pairs)]
        png = detection(series, power=power, false_alarm_rate=fa, requirement=requirement_line, bounds=bounds,
                        xlabel=axis_label(quantity_name, shown))
        caption = (f"Detection probability against {quantity_name}: the share of each sweep level's runs flagged by "
                   f"the threshold that flags {fa:.0%} of the reference's runs, with its 95 % interval (bootstrap, "
                   "widened to the exact binomial interval of the count), per measured feature (filled) and with "
                   f"ideal sensors (open); {n} ok runs per level or more. The bar above the points is each "
                   f"feature's minimum detectable {quantity_name} within its 95 % bounds, named with the verdict: "
                   "GO where the bar ends at or below the requirement line, NO-GO where it starts at or above it. "
                   "Points are the levels that were run, drawn side by side; nothing is drawn between them, where no "
                   f"run was made{where} (its detection probability is the false-alarm rate by construction).")
        return png, caption
    # below the detection floor: no detection probability, but each level's mean with its interval (issue 42)
    floor = int(analysis.attrs.get("min_detection_runs", 59))
    reference = next(d for d, level in zip(sweep, levels, strict=True) if level == 0.0)
    bands = tuple((f"{f}: mean of the reference {reference}, 95 % interval",
                   *(float(v) * factor for v in analysis["feature_mean_ci"].sel(feature=f, dataset=reference).values),
                   f"C{k}") for k, (f, _) in enumerate(pairs))
    png = detection(series, power=math.nan, false_alarm_rate=math.nan, requirement=requirement_line, bounds=[],
                    xlabel=axis_label(quantity_name, shown), ylabel=axis_label("feature mean", unit), bands=bands)
    caption = (f"NO DATA for a detection verdict: {n} ok runs per sweep level, {floor} needed for a detection "
               "threshold. Instead, each level's feature mean with its 95 % Student t interval (flagged: below "
               f"{int(analysis.attrs.get('min_ok_runs', 20))} runs the interval rests on a normal shape so few runs "
               "cannot check), per measured feature (filled) and with ideal sensors (open); the band of the feature's "
               "colour is the reference's mean: a level whose interval clears it is told apart from the reference on "
               f"average, which is not yet detection in a single test{where} (its mean is the band).")
    return png, caption

