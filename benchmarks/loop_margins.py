"""Cost of the per-run loop margins (twin.control.margins) against the cost of the run itself (issue 19).

Computes the margins of the sampled runs of the thesis study (campaigns.bench.adapter.run_margins: parameters, scene,
all four loops) and times one 10 s thesis run (campaigns.bench.adapter.simulate_run, after compilation), both in CPU
time of this process (``time.process_time``: less sensitive than wall time to the other processes of a loaded
machine) and in wall time. The requirement: margins under 5 % of a run.
Usage: python benchmarks/loop_margins.py [--runs N] [--quick]
"""

import argparse
import statistics
import time
from pathlib import Path

from machine import header

import campaigns
from campaigns.bench.adapter import run_margins, simulate_run
from campaigns.runner.execution import build_request
from campaigns.runner.sampling import sample

SPEC = Path(campaigns.__file__).parent / "specs" / "thesis_backlash.toml"


def _timed(function, *args):
    cpu, wall = time.process_time(), time.perf_counter()
    function(*args)
    return time.process_time() - cpu, time.perf_counter() - wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=20, help="sampled runs per data set whose margins are timed")
    parser.add_argument("--quick", action="store_true", help="3 runs per data set, one short simulated run")
    args = parser.parse_args()
    runs = 3 if args.quick else args.runs
    header("loop margins per run against the run's own cost", args.quick)
    spec = campaigns.load_spec(SPEC).model_copy(update={"runs_per_dataset": runs})
    samples = sample(spec)
    requests = [build_request(spec, samples, d, i) for d in range(len(spec.datasets)) for i in range(runs)]
    run_margins(requests[0])  # first call: imports, thread-pool discovery, numba-compiled pneumatics
    margins = [_timed(run_margins, r) for r in requests]
    cpu = statistics.median(c for c, _ in margins)
    wall = statistics.median(w for _, w in margins)
    print(f"# margins of {len(requests)} sampled runs (7 data sets x {runs}); median per run")
    print(f"margins      cpu {cpu * 1e3:8.2f} ms   wall {wall * 1e3:8.2f} ms")
    request = requests[0]
    if args.quick:
        request = request.__class__(**{**request.__dict__, "solver": {**request.solver, "duration": 1.0}})
    simulate_run.warm_up(request)
    run_cpu, run_wall = _timed(simulate_run, request)
    scale = 1.0 if not args.quick else 10.0  # a thesis run lasts 10 s of simulated time
    print(f"thesis run   cpu {run_cpu * scale:8.3f} s    wall {run_wall * scale:8.3f} s"
          + ("   (1 s run x 10)" if args.quick else ""))
    print(f"ratio        cpu {100 * cpu / (run_cpu * scale):8.2f} %    wall {100 * wall / (run_wall * scale):8.2f} %"
          "   (requirement: < 5 %)")


if __name__ == "__main__":
    main()
