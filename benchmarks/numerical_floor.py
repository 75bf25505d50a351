"""Numerical sensitivity floor of the thesis data sets: the spread of tight runs that differ in nothing that matters.

Per data set (thesis campaign fidelity, 10 s, nominal parameters, noise seed 0): RK4 at six converged steps that
divide the 125 us drive period, and at 7.8125 us with the backlash moved by a few picometres
(campaigns.bench.reference_ensemble). Prints each feature's spread (n, range, standard deviation with its 95 %
chi-square interval), with ``--results`` the share of a campaign's per-data-set variance the numerical spread could
account for, and the lines of campaigns/bench/numerical_floor.toml (the floor is the range). No solver is judged against
the ensemble: the per-run rule is retired, a configuration is judged at campaign level
(campaigns.statistics.accuracy_rule, docs/accuracy.md).

    python benchmarks/numerical_floor.py [--results /path/to/thesis/results.nc]
    python benchmarks/numerical_floor.py --quick     # ds2, 0.5 s, two steps: checks the pipeline (seconds)
"""

from __future__ import annotations

import argparse
import os

import numpy as np
import xarray as xr
from machine import header
from single_run import THESIS_DATASETS, THESIS_OUTPUTS

import twin
from campaigns.bench.reference_ensemble import REFERENCE_STEPS, reference_ensemble
from campaigns.statistics.paired_comparison import ensemble_spread

FEATURES = ("backlash_feature", "backlash_feature_true", "backlash_hysteresis", "backlash_hysteresis_true")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--datasets", nargs="*", default=THESIS_DATASETS)
    parser.add_argument("--results", help="a thesis campaign's results.nc: the per-data-set sigma to compare with")
    parser.add_argument("--quick", action="store_true", help="ds2, 0.5 s, two steps, no perturbation")
    args = parser.parse_args()
    header("numerical sensitivity floor: tight runs that differ only in their step or by picometres", args.quick)
    params = twin.load_parameters()
    datasets, steps, duration = (["ds2"], REFERENCE_STEPS[3::2], 0.5) if args.quick else \
        (args.datasets, REFERENCE_STEPS, None)
    campaign = xr.open_dataset(args.results) if args.results else None
    toml = []
    for name in datasets:
        scene = twin.load_scene(name)
        ensemble, _ = reference_ensemble(scene, params, steps=steps, gap_perturbations=() if args.quick else None,
                                         features=FEATURES, outputs=THESIS_OUTPUTS, duration=duration)
        print(f"\n{name} (load average {os.getloadavg()[0]:.1f}); members: {', '.join(ensemble.member.values)}")
        toml.append(f"[{name}]")
        for feature in FEATURES:
            spread = ensemble_spread(ensemble[feature].values)
            line = (f"  {feature:25s} n {spread['n']:2d}, {spread['min'] * 1e6:9.4f} to {spread['max'] * 1e6:9.4f} um, "
                    f"range {spread['range'] * 1e6:.4f} um, std {spread['std'] * 1e6:.4f} um "
                    f"(95 % {spread['std_lower'] * 1e6:.4f}-{spread['std_upper'] * 1e6:.4f})")
            if campaign is not None and name in campaign.dataset.values:
                values = campaign[feature].sel(dataset=name).where(campaign.status.sel(dataset=name) == "ok").values
                sigma = float(np.nanstd(values, ddof=1))
                line += (f"; campaign sigma {sigma * 1e6:.3f} um (n {int(np.isfinite(values).sum())}): numerical share "
                         f"of the variance {spread['std'] ** 2 / sigma ** 2:.2f} "
                         f"({spread['std_lower'] ** 2 / sigma ** 2:.2f}-{spread['std_upper'] ** 2 / sigma ** 2:.2f})")
            print(line)
            toml.append(f"{feature} = {spread['range']:.3e}  # m, n = {spread['n']}")
    print("\ncampaigns/numerical_floor.toml (floor = range of the ensemble):\n" + "\n".join(toml))


if __name__ == "__main__":
    main()
