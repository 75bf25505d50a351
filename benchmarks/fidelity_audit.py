"""Acceptance of the automatic fidelity: auto against full on the seven thesis data sets.

For each data set, ``--runs`` sampled runs (Table 9.5 uncertainties, thesis seed) at
``fidelity="auto"`` and the same runs at full fidelity; prints per feature the audit's verdict statement
(campaigns.bench.fidelity_audit: the paired mean shift's 95 % t interval against the 0.1 um tolerance and the
scene's numerical floor), the largest paired difference, the Monte Carlo error of the mean, the KS p-value,
and per data set the speedup (campaign wall time per run, and the simulation alone on one run).

    python benchmarks/fidelity_audit.py --runs 200 --out out/fidelity_acceptance
    python benchmarks/fidelity_audit.py --quick     # 5 runs of ds2 and ds5 (the audit's floor): the pipeline only
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from machine import header

import twin
from campaigns.bench.fidelity_audit import AUDIT_MIN_PAIRS
from campaigns.bench.scene_audit import audit_scene

DATASETS = ("ds1", "ds2", "ds3", "ds4", "ds5", "ds6", "ds7")


def simulation_speedup(scene: str, repeats: int) -> float:
    """Median simulation wall time, full over auto (``attrs["wall_time"]``: the compiled loop only)."""
    def median(fidelity):
        twin.simulate(scene, fidelity=fidelity, duration=0.01)  # compile
        times = sorted(twin.simulate(scene, fidelity=fidelity).attrs["wall_time"] for _ in range(repeats))
        return times[len(times) // 2]
    return median("full") / median("auto")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("out/fidelity_acceptance"))
    parser.add_argument("--datasets", nargs="*", default=DATASETS)
    parser.add_argument("--quick", action="store_true",
                        help="the audit's fewest runs (5) of ds2 and ds5 in a temporary directory (not an acceptance)")
    args = parser.parse_args()
    header("fidelity audit: auto against full fidelity on the thesis data sets", args.quick)
    if args.quick:
        args.runs, args.datasets = AUDIT_MIN_PAIRS, ["ds2", "ds5"]
        args.out = Path(tempfile.mkdtemp(prefix="fidelity_audit_quick_"))
    print(f"{'set':4s} {'feature':24s} {'max paired':>11s} {'MC error':>9s} {'KS p':>5s}  verdict")
    for name in args.datasets:
        start = time.perf_counter()
        audit = audit_scene(name, args.out / name, runs=args.runs, workers=args.workers)
        sim = simulation_speedup(name, 1 if args.quick else 3)
        # a data set whose automatic choice is the full model is not re-run: its rows carry no paired figures
        paired = "max_paired_difference" in audit
        for feature in audit.feature.values:
            row = audit.sel(dataset=name, feature=feature)
            figures = (f"{float(row.max_paired_difference) * 1e6:9.4f}µm {float(row.sampling_error) * 1e6:7.4f}µm "
                       f"{float(row.ks_pvalue):5.2f}" if paired else f"{'–':>11s} {'–':>9s} {'–':>5s}")
            print(f"{name:4s} {feature:24s} {figures}  {row.statement.item()}")
        campaign = f"x{float(audit.speedup.sel(dataset=name)):.2f}" if paired else "– (not re-run)"
        print(f"     speedup campaign {campaign}, simulation x{sim:.2f}; "
              f"auto: {audit.attrs['fidelity_auto']}  ({time.perf_counter() - start:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
