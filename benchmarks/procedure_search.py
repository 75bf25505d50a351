"""Procedure search: screening then finalists, against evaluating every candidate with the full sweep, side by side.

Usage::

    python benchmarks/procedure_search.py --quick          # synthetic model, 4 candidates (CI)
    python benchmarks/procedure_search.py --candidates 8   # synthetic model, 8 candidates

Both strategies run on the synthetic model (campaigns.runner.synthetic: its answer to a procedure is known, so the best
candidate is known) with the same design, units and seeds:

* **screening** (``campaigns.workflows.procedure_search.run_search``, its default one round): every candidate screened
at two
  levels (the baseline and the requirement), the best one through the full sweep;
* **exhaustive**: every candidate through the full sweep and the within-unit analysis, the best by the analysis's
  bounds of the 95th-percentile unit.

Printed: runs, wall time and the candidate each strategy picks (and the known best), with the ratios. The runs
ratio is the cost ratio on the bench, where runs dominate; on the synthetic model the campaigns' fixed costs (a
cluster start each) dominate the wall time. docs/campaigns.md, "Procedure search", has the figures.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from campaigns import analyze, run_campaign  # noqa: E402
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, procedure_effect, synthetic_run  # noqa: E402
from campaigns.statistics.within_unit_floors import MIN_REPEATS, MIN_UNITS  # noqa: E402
from campaigns.workflows.procedure_search import (  # noqa: E402
    DESIGN_STREAM,
    design,
    load_search,
    plan_runs,
    run_search,
    write_candidate_spec,
)

#: The tests' synthetic search (its campaign beside it): 4 candidates, the reference and one anchor among them.
SEARCH = ROOT / "tests" / "campaigns" / "data" / "synthetic_search.toml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="4 candidates (CI)")
    parser.add_argument("--candidates", type=int, default=8)
    args = parser.parse_args()
    candidates = 4 if args.quick else args.candidates
    with tempfile.TemporaryDirectory() as scratch:
        root = Path(scratch)
        campaign = SEARCH.parent / "synthetic_search_campaign.toml"
        (root / "search.toml").write_text(
            SEARCH.read_text().replace('campaign = "synthetic_search_campaign.toml"', f'campaign = "{campaign}"')
            .replace("candidates = 4", f"candidates = {candidates}").replace("runs = 4000", "runs = 100000"))
        spec = load_search(root / "search.toml", catalog=SYNTHETIC_CATALOG)
        known = {c.name: (lambda e: e[1] / e[0])(procedure_effect(c.knobs)) for c in design(spec)}
        best_known = min(known, key=known.get)

        start = time.perf_counter()
        path = run_search(spec, root / "screening", workers=1, progress=False, run_function=synthetic_run,
                          catalog=SYNTHETIC_CATALOG)
        screening_wall = time.perf_counter() - start
        with xr.open_dataset(path, engine="netcdf4") as ds:
            screening_best = ds.attrs["best"]

        start, exhaustive_runs, figures = time.perf_counter(), 0, {}
        for candidate in design(spec):
            directory = root / "exhaustive" / candidate.name
            campaign = write_candidate_spec(spec, candidate, "final", spec.budget.repeats, directory,
                                            SYNTHETIC_CATALOG)
            results = run_campaign(campaign, directory / "final", workers=1, progress=False,
                                   run_function=synthetic_run, catalog=SYNTHETIC_CATALOG)
            exhaustive_runs += len(campaign.datasets) * campaign.runs_per_dataset
            with xr.open_dataset(analyze(results), engine="netcdf4") as analysis:
                bounds = analysis["within_unit_minimum_detectable_backlash_ci"].sel(
                    unit_quantile=0.95, feature="backlash_feature").values
            figures[candidate.name] = (bounds[1] if math.isfinite(bounds[1]) else math.inf, bounds[0])  # as the search
        exhaustive_wall = time.perf_counter() - start
        exhaustive_best = min(figures, key=figures.get)
    tied = [name for name, figure in figures.items() if figure == figures[exhaustive_best]]

    print(f"procedure search on the synthetic model: {candidates} candidates, {MIN_UNITS} units, "
          f"{MIN_REPEATS} repeats; design stream {DESIGN_STREAM}")
    print(f"  known best (smallest noise/sensitivity of campaigns.runner.synthetic.procedure_effect): {best_known}")
    print(f"  {'strategy':<12} {'runs':>7} {'wall [s]':>9}  best")
    print(f"  {'screening':<12} {plan_runs(spec):>7} {screening_wall:>9.1f}  {screening_best}")
    print(f"  {'exhaustive':<12} {exhaustive_runs:>7} {exhaustive_wall:>9.1f}  {exhaustive_best}"
          + (f" (its sweep brackets tie {', '.join(tied)}: the first is taken)" if len(tied) > 1 else ""))
    print(f"  ratio screening/exhaustive: runs {plan_runs(spec) / exhaustive_runs:.2f}, "
          f"wall {screening_wall / exhaustive_wall:.2f}; same best: {screening_best == exhaustive_best}, "
          f"screening finds the known best: {screening_best == best_known}")


if __name__ == "__main__":
    main()
