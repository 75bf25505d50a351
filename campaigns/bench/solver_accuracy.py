"""The acceptance study of the default configuration: the accuracy rule (:mod:`campaigns.statistics.accuracy_rule`)
applied to campaigns.

One call (:func:`campaign_accuracy`; ``benchmarks/accuracy_acceptance.py`` on the command line) runs the thesis spec
under the tight reference and under every candidate configuration with the same seeds, so run i of a data set has the
same parameters and noise everywhere; analyses each campaign (``analysis.nc``: verdicts, sensitivity rankings); and
judges each candidate against the reference with :func:`campaigns.statistics.accuracy_rule.judge_accuracy`. It writes
``campaign_accuracy.nc`` (CF) and ``campaign_accuracy.md`` (the table of docs/accuracy.md, "Acceptance of the
default") and returns the judgement.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from campaigns.analysis.campaign_analysis import analyze
from campaigns.bench.campaign import load_spec, run_campaign
from campaigns.runner.files import write_netcdf
from campaigns.runner.spec import CampaignSpec, FidelityAudit, Observability, Solver, Traces
from campaigns.statistics.accuracy_rule import MIN_PAIRED_RUNS, REFERENCE_SOLVER, judge_accuracy

#: The thesis study (Sec. 9.4, Table 9.5 uncertainties, data sets 1-7): the spec the rule is stated for.
THESIS_SPEC = Path(__file__).parents[1] / "specs" / "thesis_backlash.toml"


@dataclass(frozen=True)
class Configuration:
    """A solver configuration of the study: a file-safe ``name``, what the tables call it, and its solver options
    (:class:`campaigns.runner.spec.Solver` fields)."""

    name: str
    description: str
    solver: dict = field(default_factory=dict)


REFERENCE = Configuration("reference", "full fidelity, RK4 at 15.625 us (the tight reference)", REFERENCE_SOLVER)
CANDIDATES = (
    # the twin's default, whatever it is when the study runs: the step the method and the fidelity choose
    Configuration("new_default", "the default: RK4 at its default step, automatic fidelity (quasi-static screw axial)",
                  {"integrator": "rk4", "dt": None, "fidelity": "auto"}),
    Configuration("previous_default", "the previous default: RK4 at 62.5 us, automatic fidelity with the dynamic "
                                      "screw axial", {"integrator": "rk4", "dt": 6.25e-5,
                                                      "fidelity": {"default": "auto", "screw_axial": "dynamic"}}),
)


def variant(spec: CampaignSpec, configuration: Configuration, *, runs: int, datasets: Sequence[str] | None = None,
            features: Sequence[str] | None = None, scenes: dict[str, str] | None = None) -> CampaignSpec:
    """The spec solved under ``configuration``: ``runs`` runs of ``datasets`` (default all), ``features`` (default the
    spec's), each data set's scene replaced where ``scenes`` names another (e.g. a shortened copy), no traces and no
    fidelity audit (the study is the audit). The observability sweep is kept when all its data sets are run, so the
    analysis states its requirement verdicts."""
    scenes = scenes or {}
    chosen = [d.model_copy(update={"scene": scenes[d.name]}) if d.name in scenes else d
              for d in spec.datasets if datasets is None or d.name in datasets]
    names = {d.name for d in chosen}
    observability = spec.observability if set(spec.observability.sweep) <= names else Observability()
    return spec.model_copy(update={
        "name": f"{spec.name}_{configuration.name}",
        "datasets": chosen,
        "runs_per_dataset": runs,
        "features": list(features or spec.features),
        "solver": Solver(**{**spec.solver.model_dump(), **configuration.solver}),
        "traces": Traces(),
        "observability": observability,
        "fidelity_audit": FidelityAudit(runs=0),
    })


def campaign_accuracy(out_dir: str | Path, spec: CampaignSpec | str | Path = THESIS_SPEC, *,
                      runs: int = MIN_PAIRED_RUNS, datasets: Sequence[str] | None = None,
                      features: Sequence[str] | None = None, scenes: dict[str, str] | None = None,
                      reference: Configuration = REFERENCE, candidates: Sequence[Configuration] = CANDIDATES,
                      min_pairs: int = MIN_PAIRED_RUNS, workers: int = 2, resume: bool = False, run_function=None,
                      progress: Callable[[str], None] = print) -> xr.Dataset:
    """Run the reference and every candidate over the same sampled runs, analyse them and judge each candidate.

    Parameters
    ----------
    out_dir : str or Path
        One campaign directory per configuration (``results.nc``, ``analysis.nc``), and ``campaign_accuracy.nc``
        and ``campaign_accuracy.md``.
    spec : CampaignSpec, str or Path
        The spec or its file (default: the thesis study).
    runs, datasets, features, scenes
        As :func:`variant`.
    min_pairs : int
        Fewest paired runs for a verdict (the rule's 200; fewer only to exercise the pipeline).
    resume : bool
        Continue interrupted campaigns in ``out_dir`` (:func:`campaigns.bench.campaign.run_campaign`).
    run_function : callable, optional
        The campaigns' run function (default: the bench twin).
    progress : callable
        Receives one line per configuration and per stage of its campaign (compile, cluster start, runs, ...), and
        every verdict statement.

    Returns
    -------
    xarray.Dataset
        :func:`campaigns.statistics.accuracy_rule.judge_accuracy` per ``candidate`` (with ``candidate_verdict`` and
        ``candidate_statement``), and per ``configuration`` its description, the solvers its runs recorded and their
        mean wall time.
    """
    out = Path(out_dir)
    spec = spec if isinstance(spec, CampaignSpec) else load_spec(spec)
    results, analyses = {}, {}
    for configuration in (reference, *candidates):
        run_spec = variant(spec, configuration, runs=runs, datasets=datasets, features=features, scenes=scenes)
        progress(f"{configuration.name}: {len(run_spec.datasets)} data sets x {runs} runs "
                 f"({configuration.description})")
        path = run_campaign(run_spec, out / configuration.name, workers=workers, resume=resume, progress=False,
                            announce=lambda stage, message: progress(f"  {stage}: {message}"),
                            **({"run_function": run_function} if run_function is not None else {}))
        results[configuration.name] = xr.load_dataset(path)
        analyses[configuration.name] = xr.load_dataset(analyze(path))
    judgements = {c.name: judge_accuracy(results[c.name], results[reference.name], run_spec.features,
                                         candidate_analysis=analyses[c.name],
                                         reference_analysis=analyses[reference.name], min_pairs=min_pairs)
                  for c in candidates}
    judged = xr.concat([j.expand_dims(candidate=[name]) for name, j in judgements.items()], dim="candidate",
                       combine_attrs="drop_conflicts")
    judged["candidate_verdict"] = ("candidate", np.array([j.attrs["verdict"] for j in judgements.values()],
                                                         dtype=object),
                                   {"long_name": "the rule over every data set, feature, analysis verdict and ranking"})
    judged["candidate_statement"] = ("candidate", np.array([j.attrs["statement"] for j in judgements.values()],
                                                           dtype=object),
                                     {"long_name": "the candidate's verdict and what has it (printed verbatim)"})
    judged = judged.merge(_configurations(results, (reference, *candidates)))
    judged.attrs.update(reference=reference.name, spec=spec.name, runs_per_dataset=runs)
    write_netcdf(judged, out / "campaign_accuracy.nc", title="BenchTwin acceptance of the default configuration",
                 history=f"campaigns.bench.solver_accuracy.campaign_accuracy: {runs} runs per data set, "
                         f"{len(candidates)} candidate(s) against {reference.name}")
    (out / "campaign_accuracy.md").write_text(markdown_table(judged))
    for name in judgements:
        progress(f"{name}: {judged.candidate_statement.sel(candidate=name).item()}")
        for d in judged.dataset.values:
            for f in judged.feature.values:
                progress(f"  {d} {f}: {judged.statement.sel(candidate=name, dataset=d, feature=f).item()}")
    return judged


def _configurations(results: dict[str, xr.Dataset], configurations: Sequence[Configuration]) -> xr.Dataset:
    """Per configuration: its description, the solvers its runs recorded (``results.nc`` ``integrator``) and the
    mean wall time of its ok runs (what a run costs under that configuration on this machine)."""
    def solvers(ds: xr.Dataset) -> str:
        if "integrator" not in ds:
            return "not recorded"
        return ", ".join(sorted({str(v) for v in ds["integrator"].values.ravel() if str(v)})) or "not recorded"

    def mean_wall_time(ds: xr.Dataset) -> float:
        times = ds.wall_time.where(ds.status == "ok").values
        return float(np.nanmean(times)) if np.isfinite(times).any() else math.nan

    names = [c.name for c in configurations]
    return xr.Dataset(
        {
            "configuration_description": ("configuration", np.array([c.description for c in configurations],
                                                                    dtype=object),
                                          {"long_name": "what the configuration is"}),
            "configuration_solvers": ("configuration", np.array([solvers(results[n]) for n in names], dtype=object),
                                      {"long_name": "the method and step of its runs, as results.nc records them"}),
            "configuration_wall_time": ("configuration", [mean_wall_time(results[n]) for n in names],
                                        {"units": "s", "long_name": "mean wall time of an ok run (results.nc "
                                                                    "wall_time; depends on the machine's load)"}),
        },
        coords={"configuration": np.array(names, dtype=object)},
    )


def _interval(cell: xr.Dataset, name: str, scale: float, spec: str) -> str:
    """``value (lower to upper)`` of ``name`` and its interval, or a dash where the data do not resolve it."""
    value, lower, upper = (float(cell[f"{name}{suffix}"]) * scale for suffix in ("", "_lower", "_upper"))
    return f"{value:{spec}} ({lower:{spec}} to {upper:{spec}})" if np.isfinite(lower) else "–"


def markdown_table(judged: xr.Dataset) -> str:
    """The acceptance table of docs/accuracy.md: per candidate its verdict, then per data set and feature n, the mean
    shift and the sd ratio with their 95 % intervals, the ranking check and the verdict; then the analysis verdicts
    that changed. A cell the data do not resolve (insufficient data) shows no number."""
    reference = judged.attrs.get("reference", "reference")
    lines = []
    for candidate in judged.candidate.values:
        c = judged.sel(candidate=candidate)
        config = judged.sel(configuration=candidate)
        lines += [f"### {candidate}: {c.candidate_verdict.item()}", "",
                  f"{config.configuration_description.item()} ({config.configuration_solvers.item()}) against "
                  f"{reference} ({judged.configuration_solvers.sel(configuration=reference).item()}); "
                  f"{c.candidate_statement.item()}.", "",
                  "| data set | feature | n | mean shift [µm] (95 % t interval) | sd ratio (95 % jackknife interval) "
                  "| top-3 ranking | verdict |",
                  "|---|---|---|---|---|---|---|"]
        for d in judged.dataset.values:
            for f in judged.feature.values:
                cell = c.sel(dataset=d, feature=f)
                ranking = ({"met": "unchanged", "not met": f"changed: {cell.ranking_reference.item()} → "
                                                          f"{cell.ranking_candidate.item()}"}
                           .get(cell.ranking_verdict.item(), cell.ranking_verdict.item()))
                lines.append(
                    f"| {d} | `{f}` | {int(cell.n)} | "
                    f"{_interval(cell, 'mean_shift', 1e6, '+.4f')} | {_interval(cell, 'sd_ratio', 1.0, '.3f')} | "
                    f"{ranking} | {cell.verdict.item()} |")
        changed = [f"`{check}`: {c.verdict_reference.sel(verdict_check=check).item()} → "
                   f"{c.verdict_candidate.sel(verdict_check=check).item()}"
                   for check in judged.verdict_check.values
                   if c.verdict_unchanged.sel(verdict_check=check).item() == "not met"]
        unjudged = int((c.verdict_unchanged == "insufficient data").sum())
        lines += ["", f"Analysis verdicts ({judged.sizes['verdict_check']}): "
                  + ("; ".join(changed) if changed else
                     f"not compared (insufficient data: fewer than {judged.attrs.get('min_paired_runs')} paired runs)"
                     if unjudged else "all unchanged") + ".", ""]
    return "\n".join(lines)
