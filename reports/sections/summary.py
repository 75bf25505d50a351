"""Section "Campaign and provenance": the spec, the uncertainty table, the data sets and where the numbers come from."""

from __future__ import annotations

import json

import numpy as np

from reports.builder import Builder, solver_description
from reports.model import Callout, Paragraph
from reports.units import display_scale, number


def build(b: Builder):
    spec, results = b.spec, b.results
    status = results["status"].values
    n_failed = int((status != "ok").sum())
    yield Paragraph(
        f"Campaign '{spec['name']}' ran the model with parameter set '{spec['base']['parameters']}' on "
        f"{len(b.datasets)} data set(s) of {results.sizes['run']} runs each ({status.size} runs). "
        f"Each run drew {b.parameter_counts()} (Table 9.5 rows of the spec) and computed the "
        f"feature(s) {', '.join(b.features)}. Everything below is read from the stored files; no simulation was re-run."
    )
    yield Callout(
        f"{status.size - n_failed} of {status.size} runs succeeded; {n_failed} failed"
        + (" (see Failed runs)." if n_failed else "."),
        "bad" if n_failed else "good",
    )
    execution = spec.get("execution", {})
    traces = spec.get("traces", {})
    bootstrap = json.loads(b.analysis.attrs.get("bootstrap", "{}") or "{}")
    rows = [
        ("Campaign", spec["name"]),
        ("Description", spec.get("description") or "–"),
        ("Spec hash (SHA-256)", results.attrs.get("spec_hash", "–")),
        ("Parameter set", spec["base"]["parameters"]),
        ("Base scene", spec["base"]["scene"]),
        ("Features", ", ".join(b.features)),
        ("Runs per data set", str(results.sizes["run"])),
        ("Root seed", results.attrs.get("root_seed_entropy", str(spec.get("root_seed", "–")))),
        ("Seeding", results.attrs.get("seeding", "–")),
        ("Solver", solver_description(spec)),
        ("Execution", ", ".join(f"{k} = {'adaptive' if v is None else v}" for k, v in execution.items()) or "–"),
        ("Traces kept", f"{traces.get('runs_per_dataset', 0)} run(s) per data set, decimated by "
                        f"{traces.get('decimation', 1)}: {', '.join(traces.get('variables', [])) or 'none'}"),
        ("Half-range sigmas", number(results.attrs.get("half_range_sigmas"))),
        ("Results created", results.attrs.get("date_created", "–")),
        ("Campaign elapsed time", f"{number(results.attrs['execution_wall_time'])} s for "
                                  f"{results.attrs.get('execution_executed_runs', '–')} runs on "
                                  f"{results.attrs.get('execution_workers', '–')} worker(s) (last invocation)"
         if "execution_wall_time" in results.attrs else "–"),
        ("Analysis",
         "computed in memory from results.nc (no analysis.nc given)" if b.inputs.analysis_computed else "analysis.nc"),
        ("Bootstrap", ", ".join(f"{k} = {v}" for k, v in bootstrap.items()) or "–"),
    ]
    rows += [(f"Input file ({f.role})", f"{f.name}, SHA-256 {f.sha256}") for f in b.inputs.files]
    yield b.table("Campaign specification, solver configuration and provenance.", ("Item", "Value"), rows)

    statuses = sorted(set(status.ravel().tolist()) - {"ok"})

    def counts(label: str, s: np.ndarray, w: np.ndarray) -> list[str]:
        return ([label, str(s.size), str(int((s == "ok").sum()))] + [str(int((s == st).sum())) for st in statuses]
                + [number(np.nanmedian(w)) if np.isfinite(w).any() else "–", number(np.nansum(w))])

    rows = [counts(b.describe(n), results["status"].sel(dataset=n).values, results["wall_time"].sel(dataset=n).values)
            for n in b.datasets]
    rows.append(counts("all", status, results["wall_time"].values))
    yield b.table(
        "Data sets (scene and conditions), runs per status and wall time. Wall time is machine dependent; "
        "the total is the sum over runs (the campaign's elapsed time is shorter when workers run in parallel).",
        ["Data set", "Runs", "ok"] + statuses + ["Median wall time per run [s]", "Total wall time [s]"],
        rows,
    )

    rows = []
    for name in b.parameters:
        dist = json.loads(results[name].attrs.get("distribution", "{}") or "{}")
        unit = results[name].attrs.get("units", "")
        values = {key: dist[key] for key in ("nominal", "mean", "low", "high", "value", "sigma") if key in dist}
        # a lognormal's sigma is that of the logarithm, without unit
        log_sigma = values.pop("sigma") if dist.get("kind") == "lognormal" and "sigma" in values else None
        # one prefix for the row, chosen by its largest value: "nominal 0 µm, low -5 µm", never "nominal 0 m"
        factor, shown = display_scale(unit, list(values.values()))
        shown = "" if shown == "–" else f" {shown}"
        shape = ", ".join(f"{key} {number(value * factor)}{shown}" for key, value in values.items())
        if log_sigma is not None:
            shape += f", sigma {number(log_sigma)} (log)"
        rows.append((name, dist.get("kind", "–"), shape, dist.get("source") or "–"))
    yield b.table("Uncertain parameters (sampled per run) with their resolved distributions; the Source column "
                  "quotes the spec.",
                  ("Parameter", "Distribution", "Values", "Source"), rows)

    versions = json.loads(results.attrs.get("package_versions", "{}") or "{}")
    yield b.table("Package versions recorded when the campaign ran.", ("Package", "Version"), sorted(versions.items()))
