"""Convergence of the free-nut results (ds2, ds4, ds6, ds7) in the seal's and guides' friction regularisation speed.

Paired runs (app.studies.friction_convergence): the seal's v_th halved from 5 mm/s to 0.25 mm/s at the default
guides, the guides' from 1e-4 to 5e-6 m/s at the default seal, noise seeds 0-2, the thesis campaign's fidelity, RK4
at the largest step dividing 125 us that keeps the friction eigenvalue inside half of RK4's real-axis reach (never
above 15.625 us), the scenes' full 10 s; a step check halves the step of the smallest seal v_th on seed 0. Prints
one line per run (appended to OUT/friction_convergence.csv as it goes), then per data set and v_th the mean over
the seeds and the paired shift from the default, and writes the chart OUT/friction_convergence.png/.svg.

    python benchmarks/friction_convergence.py --out DIR            # 88 runs, ~10-20 min of CPU
    python benchmarks/friction_convergence.py --out DIR --replot   # table and chart from DIR's csv
    python benchmarks/friction_convergence.py --quick              # ds4, seed 0, 5 and 1 mm/s, 1 s: the pipeline
"""

from __future__ import annotations

import argparse
import csv
import os
import tempfile
from dataclasses import fields
from pathlib import Path

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from machine import header  # noqa: E402

import twin  # noqa: E402
from app.studies import friction_convergence as fc  # noqa: E402

CSV_NAME = "friction_convergence.csv"
COLUMNS = [f.name for f in fields(fc.Point)] + ["check"]


def _write(path: Path, row: dict) -> None:
    new = not path.exists()
    with path.open("a", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        if new:
            writer.writeheader()
        writer.writerow(row)


def _read(path: Path) -> list[dict]:
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    for row in rows:
        for key in COLUMNS:
            if key not in ("dataset", "status", "check"):
                row[key] = float(row[key])
    return rows


def run(out: Path, quick: bool) -> None:
    params = twin.load_parameters()
    plan = [("ds4", 0, s, fc.GUIDE_THRESHOLDS[0]) for s in (5.0e-3, 1.0e-3)] if quick else fc.study_plan()
    duration = 1.0 if quick else None
    jobs = [(job, None, "") for job in plan]
    if not quick:
        smallest = min(fc.SEAL_THRESHOLDS)
        jobs += [((name, 0, smallest, fc.GUIDE_THRESHOLDS[0]),
                  fc.stable_step(smallest, fc.GUIDE_THRESHOLDS[0], params) / 2.0, "half step")
                 for name in ("ds2", "ds4")]   # last: the sweeps first when the time runs out (resumed by the csv)
    path = out / CSV_NAME
    done = {(r["dataset"], int(r["seed"]), r["seal_threshold"], r["guide_threshold"], r["check"])
            for r in _read(path)} if path.exists() else set()
    for (name, seed, seal, guide), dt, check in jobs:
        if (name, seed, seal, guide, check) in done:
            continue
        point = fc.run_point(name, seed, seal, guide, params, dt=dt, duration=duration)
        _write(path, {**fc.as_rows([point])[0], "check": check})
        print(f"{name} seed {seed} seal {seal * 1e3:g} mm/s guides {guide * 1e3:g} mm/s dt {point.dt * 1e6:g} us "
              f"{point.status}: f_b {point.backlash_feature * 1e6:.3f} um, H {point.backlash_hysteresis * 1e6:.3f} um, "
              f"force error {point.force_error_rms_at_rest:.1f} N rms, nut {point.nut_speed_rms_at_rest * 1e3:.2f} "
              f"mm/s rms at rest; {point.cpu_s:.1f} s CPU (load {os.getloadavg()[0]:.1f})", flush=True)


def table(rows: list[dict]) -> None:
    sweep = [r for r in rows if not r["check"]]
    seal_default = twin.load_parameters().value("pneumatics.friction_velocity_threshold")
    guide_default = fc.GUIDE_THRESHOLDS[0]
    print("\n| data set | seal v_th [mm/s] | guides v_th [mm/s] | dt [us] | f_b [um] | shift of f_b [um] | H [um] | "
          "shift of H [um] | force error at rest [N rms] | nut speed at rest [mm/s rms / peak] | "
          "CPU per run [s, median] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in sorted({r["dataset"] for r in sweep}):
        mine = [r for r in sweep if r["dataset"] == name]
        base = {int(r["seed"]): r for r in mine
                if r["seal_threshold"] == seal_default and r["guide_threshold"] == guide_default}
        combos = sorted({(r["guide_threshold"], r["seal_threshold"]) for r in mine}, reverse=True)
        for guide, seal in combos:
            group = [r for r in mine if r["seal_threshold"] == seal and r["guide_threshold"] == guide
                     and r["status"] == "ok"]

            def mean(key, group=group):
                return np.mean([r[key] for r in group])

            def shift(key, group=group, base=base):
                d = [r[key] - base[int(r["seed"])][key] for r in group if int(r["seed"]) in base]
                return f"{np.mean(d) * 1e6:+.2f} ({np.min(d) * 1e6:+.2f} to {np.max(d) * 1e6:+.2f})"

            print(f"| {name} | {seal * 1e3:g} | {guide * 1e3:g} | {group[0]['dt'] * 1e6:g} | "
                  f"{mean('backlash_feature') * 1e6:.2f} | {shift('backlash_feature')} | "
                  f"{mean('backlash_hysteresis') * 1e6:.2f} | {shift('backlash_hysteresis')} | "
                  f"{mean('force_error_rms_at_rest'):.0f} | {mean('nut_speed_rms_at_rest') * 1e3:.2f} / "
                  f"{mean('nut_speed_peak_at_rest') * 1e3:.1f} | {np.median([r['cpu_s'] for r in group]):.1f} |")
    checks = [r for r in rows if r["check"]]
    for r in checks:
        ref = next(x for x in sweep if x["dataset"] == r["dataset"] and x["seed"] == r["seed"]
                   and x["seal_threshold"] == r["seal_threshold"] and x["guide_threshold"] == r["guide_threshold"])
        print(f"step check {r['dataset']} seed {int(r['seed'])} seal {r['seal_threshold'] * 1e3:g} mm/s: dt "
              f"{r['dt'] * 1e6:g} us against {ref['dt'] * 1e6:g} us: f_b {r['backlash_feature'] * 1e6:.3f} against "
              f"{ref['backlash_feature'] * 1e6:.3f} um, H {r['backlash_hysteresis'] * 1e6:.3f} against "
              f"{ref['backlash_hysteresis'] * 1e6:.3f} um")


def chart(rows: list[dict], path: Path) -> None:
    guide_default = fc.GUIDE_THRESHOLDS[0]
    sweep = [r for r in rows if not r["check"] and r["guide_threshold"] == guide_default and r["status"] == "ok"]
    fig, (ax, cost) = plt.subplots(2, 1, figsize=(7, 7), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    for name in sorted({r["dataset"] for r in sweep}):
        mine = [r for r in sweep if r["dataset"] == name]
        seals = sorted({r["seal_threshold"] for r in mine})
        for r in mine:
            ax.plot(r["seal_threshold"] * 1e3, r["backlash_feature"] * 1e6, ".", color="0.6")
        means = [np.mean([r["backlash_feature"] for r in mine if r["seal_threshold"] == s]) * 1e6 for s in seals]
        ax.plot(np.array(seals) * 1e3, means, "o-", label=name)
        # the median: a process's first run carries the compilation
        cpu = [np.median([r["cpu_s"] for r in mine if r["seal_threshold"] == s]) for s in seals]
        cost.plot(np.array(seals) * 1e3, cpu, "o-", label=name)
    ax.set_xscale("log")
    ax.set_ylabel("f_b, measured [um] (dots: seeds)")
    ax.legend(loc="center right", bbox_to_anchor=(1.0, 0.62))
    ax.grid(True, which="both", alpha=0.3)
    ax.set_title("free nut: f_b against the seal's friction regularisation speed", fontsize=10)
    cost.set_xscale("log")
    cost.set_yscale("log")
    cost.set_xlabel("seal v_th [mm/s] (sign(v) -> tanh(v / v_th))")
    cost.set_ylabel("CPU per run [s], median")
    ticks = sorted({r["seal_threshold"] * 1e3 for r in sweep})
    cost.set_xticks(ticks, [f"{t:g}" for t in ticks])
    cost.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    cost.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    for suffix in (".png", ".svg"):
        fig.savefig(path.with_suffix(suffix), dpi=120, metadata={"Date": None} if suffix == ".svg" else None)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="folder of the csv and the chart (created; with --quick: a temporary folder "
                                      "unless given)")
    parser.add_argument("--replot", action="store_true", help="table and chart from the csv only")
    parser.add_argument("--quick", action="store_true", help="ds4, seed 0, 5 and 1 mm/s, 1 s")
    args = parser.parse_args()
    if args.out is None and not args.quick:
        parser.error("--out is required (the folder of the csv and the chart), except with --quick")
    out = Path(args.out) if args.out is not None else Path(tempfile.mkdtemp(prefix="friction_convergence_"))
    if not args.replot and (out / CSV_NAME).exists():
        parser.error(f"{out / CSV_NAME} exists: --replot reads it, or give another --out (runs are appended as "
                     "they finish, and two studies must not share one file)")
    out.mkdir(parents=True, exist_ok=True)
    header("friction regularisation convergence on the free-nut data sets", args.quick)
    if not args.replot:
        run(out, args.quick)
    rows = _read(out / CSV_NAME)
    table(rows)
    chart(rows, out / "friction_convergence.png")


if __name__ == "__main__":
    main()
