"""Section "Model-form study": what each modelling assumption varied does to the features and to the verdicts
(issue 33), and the page-1 sentence naming the assumption that moves the verdicts most.

The table is :func:`campaigns.analysis.model_form.model_form_dataset` of the report's results and analysis: the function
that wrote ``model_form.nc`` beside ``analysis.nc``, so the numbers are those of the file. Every verdict and the
sentence are quoted from it, never composed here; a shift is shown only where its interval resolves it.
"""

from __future__ import annotations

import json
from weakref import WeakKeyDictionary

from campaigns.analysis import model_form
from campaigns.statistics.detection import printed_estimate
from reports.builder import Builder
from reports.model import Callout, Paragraph, Table
from reports.phrases import INSUFFICIENT, VERDICT_TONES

#: Tone of the page-1 sentence: a changed verdict is a finding against the conclusions' robustness.
_CHANGED_TONE = VERDICT_TONES["not met"]


#: The table of each report being built, computed once: page 1 and the section both read it.
_TABLES: WeakKeyDictionary = WeakKeyDictionary()


def _table(b: Builder):
    """The model-form table of the campaign, or None when the campaign is not a model-form study."""
    if b not in _TABLES:
        _TABLES[b] = model_form.model_form_dataset(b.results, b.analysis) if model_form.is_model_form(b.results) \
            else None
    return _TABLES[b]


def _changed(table) -> bool:
    return bool((table["verdict_change"].values == model_form.VERDICT_CHANGE.index("changed")).any())


def page_one(b: Builder, executive) -> tuple:
    """The executive summary's blocks with the sentence of page 1 (the assumption that moves the verdicts or, if none
    does, the features most) after its verdicts, before its first table: a long data-set table would push it to
    page 2."""
    blocks = tuple(executive)
    table = _table(b)
    if table is None:
        return blocks
    first_table = next((k for k, block in enumerate(blocks) if isinstance(block, Table)), len(blocks))
    sentence = Callout(f"Model-form study: {table.attrs['headline']}", _CHANGED_TONE if _changed(table) else "info",
                       "model_form")
    return blocks[:first_table] + (sentence,) + blocks[first_table:]


def _cell(table, variant: str, dataset: str, feature: str, runs: int) -> str:
    """A shift as the data resolve it: the value with its interval, only the interval, or why there is none; with
    the runs it rests on when fewer than the ``runs`` of a data set (failed runs: the survivors may not represent the
    data set)."""
    cell = table.sel(variant=variant, dataset=dataset, feature=feature)
    status = model_form.SHIFT_STATUS[int(cell["shift_status"])]
    if status == "not_run":
        return "–"
    if status == "insufficient_data":
        return f"{INSUFFICIENT} (n = {int(cell['n_variant'])}, {int(cell['n_baseline'])})"
    lower, upper = (float(v) for v in cell["mean_shift_ci"].values)
    unit = str(table["feature_units"].sel(feature=feature).item())
    n = min(int(cell["n_variant"]), int(cell["n_baseline"]))
    runs_note = f"; n = {n} of {runs}" if n < runs else ""
    if status == "not_resolved":
        low, high = model_form.shown_quantities((lower, upper), 0.5 * (upper - lower), unit)
        return f"not resolved: within {low} to {high}{runs_note}"
    value = printed_estimate(float(cell["mean_shift"]), (lower, upper))
    (shown,) = model_form.shown_quantities((value,), 0.5 * (upper - lower), unit, extra=0)
    low, high = model_form.shown_quantities((lower, upper), 0.5 * (upper - lower), unit)
    return f"{'+' if value >= 0 else ''}{shown} ({low} to {high}{runs_note})"


def build(b: Builder):
    table = _table(b)
    if table is None:
        yield Callout("This campaign is not a model-form study (no data set is a one-at-a-time variant named "
                      "<baseline>__<label>). Run `twin campaign run campaigns/specs/model_form.toml --analyze` for "
                      "the table of what each modelling assumption does to the features and the verdicts.")
        return
    confidence = float(table.attrs["confidence"])
    assumptions = [f"{a} ({v} in the baseline, {w} in the variant)" for a, v, w in zip(
        table["assumption"].values, table["baseline_value"].values, table["variant_value"].values, strict=True)]
    yield Paragraph(
        "Each variant data set is a baseline data set with one modelling assumption changed: "
        + "; ".join(assumptions) + ". The shift is the variant's mean of a feature minus the baseline's, with its "
        f"{confidence * 100:g} % interval: where the variant takes its baseline's seeds (paired: run i of both is "
        "the same unit with the same noise record under the two assumptions) the t interval of the run-by-run "
        "differences, otherwise Welch's; a shift whose interval holds zero is shown as its interval only. The "
        "requirement verdict of the observability sweep is recomputed with every sweep data set replaced by its "
        "variant, with the analysis's settings. docs/model.md, Model-form study, gives each assumption's range and "
        "its source.")
    yield Callout(table.attrs["headline"], _CHANGED_TONE if _changed(table) else "info")
    features = [str(f) for f in table["feature"].values]
    rows = [(str(table["assumption"].values[i]), str(variant), feature,
             str(table["baseline_verdict"].sel(feature=feature).item()),
             str(table["variant_verdict"].sel(variant=variant, feature=feature).item()),
             model_form.VERDICT_CHANGE[int(table["verdict_change"].sel(variant=variant, feature=feature))]
             .replace("_", " "))
            for i, variant in enumerate(table["variant"].values) for feature in features]
    yield b.table("Requirement verdict of the observability sweep under each variant against the baseline's "
                  "(not compared: insufficient data on either side).",
                  ("Assumption", "Variant", "Feature", "Baseline verdict", "Variant verdict", "Change"), rows,
                  muted=[r[-1] == "not compared" for r in rows])
    insufficient = model_form.SHIFT_STATUS.index("insufficient_data")
    for variant in table["variant"].values:
        part = table.sel(variant=variant)
        datasets = [str(d) for d in part["dataset"].values
                    if (part["shift_status"].sel(dataset=d).values != model_form.SHIFT_STATUS.index("not_run")).any()]
        rows = [(d, *(_cell(table, variant, d, f, b.results.sizes["run"]) for f in features)) for d in datasets]
        fixed = json.loads(str(part["variant_parameters"].item()) or "{}")
        fixes = f" The variant fixes {', '.join(f'{k} = {v:g}' for k, v in fixed.items())} (SI units)." if fixed else ""
        yield b.table(f"Shift of each feature's mean with {variant} against the baseline, per data set, with its "
                      f"{confidence * 100:g} % interval ({part['pairing'].item()}).{fixes}", ("Data set", *features),
                      rows,
                      muted=[bool((part["shift_status"].sel(dataset=d).values == insufficient).all())
                             for d in datasets])
