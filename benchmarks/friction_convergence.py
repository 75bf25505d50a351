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

The acceptance study (issue 41, "done when"): paired runs of the thesis campaign's own sampled runs under the arms of
app.studies.friction_convergence.acceptance_arms, at the campaign's step (RK4, 62.5 us on these data sets) and half
of it, in the twin's lanes; a table of paired shifts with 95 % intervals and verdicts on +-0.05 um, and the chart
OUT/friction_acceptance.png (f_b against the seal's law, the halvings against the tolerance, the CPU per run);
--save-combined writes the folder's study as one file (docs/figures keeps it for --replot):

    python benchmarks/friction_convergence.py --acceptance 0:100 --out DIR     # ~7 min of CPU; 100:200 adds to it
    python benchmarks/friction_convergence.py --acceptance --replot --out DIR  # the table and chart from DIR
    python benchmarks/friction_convergence.py --acceptance --replot --out DIR --save-combined FILE

The free nut (item 4): 14 traced runs (FREE_NUT_CASES, ~25 s of CPU), their table and OUT/free_nut.png:

    python benchmarks/friction_convergence.py --free-nut --out DIR
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
import xarray as xr  # noqa: E402
from machine import header  # noqa: E402

import twin  # noqa: E402
from app.studies import friction_convergence as fc  # noqa: E402
from campaigns.statistics.accuracy_rule import MEAN_SHIFT_TOLERANCE, pairs_for_tolerance  # noqa: E402

CSV_NAME = "friction_convergence.csv"
ACCEPTANCE_PREFIX = "friction_acceptance_"
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


def run_acceptance(out: Path, runs: range, arms: list[str] | None = None, datasets: list[str] | None = None) -> None:
    """The paired acceptance study, one file per data set and run range (an interrupted study keeps its data sets);
    ``arms`` and ``datasets`` (default all) extend chosen pairings to more runs."""
    every = fc.acceptance_arms(twin.load_parameters())
    unknown = sorted(set(arms or ()) - {a.name for a in every})
    if unknown:
        raise SystemExit(f"--arms: unknown {', '.join(unknown)}; allowed: {', '.join(a.name for a in every)}")
    chosen = [a for a in every if arms is None or a.name in arms]
    tag = "" if arms is None else f"_{len(chosen)}_arms"
    for name in datasets or fc.ACCEPTANCE_DATASETS:
        path = out / f"{ACCEPTANCE_PREFIX}{name}_{runs.start}_{runs.stop}{tag}.nc"
        if path.exists():
            continue
        study = fc.paired_study(chosen, [name], runs,
                                progress=lambda line: print(f"{line} (load {os.getloadavg()[0]:.1f})", flush=True))
        study.to_netcdf(path)


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


def read_acceptance(out: Path):
    """Every acceptance file in ``out``, combined (data sets and run ranges), or None."""
    paths = sorted(out.glob(f"{ACCEPTANCE_PREFIX}*.nc"))
    if not paths:
        return None
    by_dataset: dict[str, list] = {}
    for path in paths:
        whole = xr.load_dataset(path)
        whole["cpu_per_run"] = whole.cpu_per_run.broadcast_like(whole.dt)   # files of one CPU figure per data set
        for name in whole.dataset.values:
            part = whole.sel(dataset=[name])
            part = part.isel(run=np.flatnonzero((part.status == "ok").any(("arm", "dataset")).values))
            by_dataset.setdefault(str(name), []).append(part)
    # runs and arms a file lacks are NaN, not "ok": left out of every pairing that needs them
    parts = [xr.concat(sorted(p, key=lambda x: int(x.run[0])), dim="run", join="outer") for p in by_dataset.values()]
    study = xr.concat(parts, dim="dataset", join="outer")
    study["status"] = study.status.where(study.status.notnull(), "absent").astype(str)
    return study


def write_acceptance(study, path: Path) -> None:
    """The combined study as one compressed file (what docs/figures keeps for --replot)."""
    encoding = {name: {"zlib": True, "complevel": 6} for name in study.data_vars}
    encoding["status"]["dtype"] = "S1"   # fixed-width characters, compressed (variable-length strings are not)
    study.to_netcdf(path, encoding=encoding)


def acceptance_table(study) -> None:
    """The paired shifts with their 95 % intervals and verdicts on +-0.05 um, the arms' means and CPU per run."""
    shifts = fc.paired_shifts(study)
    print("\n| comparison | data set | n | shift of f_b [um] (95 % interval) | verdict | "
          "shift of H [um] (95 % interval) | verdict | sd of the paired differences, f_b / H [um] | "
          "pairs a zero shift needs, f_b / H |")
    print("|---|---|---|---|---|---|---|---|---|")
    for pairing in shifts.pairing.values:
        row = shifts.sel(pairing=pairing)
        for name in shifts.dataset.values:
            cells = []
            for f in ("backlash_feature", "backlash_hysteresis"):
                c = row.sel(dataset=name, feature=f)
                cells.append(f"{float(c['mean']) * 1e6:+.3f} ({float(c.lower) * 1e6:+.3f} to "
                             f"{float(c.upper) * 1e6:+.3f}) | {c.verdict.item()}")
            n = int(row.n.sel(dataset=name, feature="backlash_feature"))
            sd = [float(row.sd.sel(dataset=name, feature=f)) for f in ("backlash_feature", "backlash_hysteresis")]
            print(f"| {row.description.item()} | {name} | {n} | {' | '.join(cells)} | "
                  f"{sd[0] * 1e6:.3f} / {sd[1] * 1e6:.3f} | "
                  f"{pairs_for_tolerance(sd[0])} / {pairs_for_tolerance(sd[1])} |")
    print("\n| arm | data set | dt [us] | f_b mean [um] | H mean [um] | f_b true [um] | ok runs | CPU per run [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for arm in study.arm.values:
        for name in study.dataset.values:
            cell = study.sel(arm=arm, dataset=name)
            ok = cell.status == "ok"
            print(f"| {arm} | {name} | {float(cell.dt.max()) * 1e6:g} | "
                  f"{float(cell.backlash_feature.where(ok).mean()) * 1e6:.3f} | "
                  f"{float(cell.backlash_hysteresis.where(ok).mean()) * 1e6:.3f} | "
                  f"{float(cell.backlash_feature_true.where(ok).mean()) * 1e6:.3f} | {int(ok.sum())} | "
                  f"{float(cell.cpu_per_run.mean()):.3f} |")


def acceptance_chart(study, path: Path) -> None:
    """Three panels: f_b against the seal's law (the regularised seal at v_th and v_th / 2, the elasto-plastic seal,
    each as the paired shift from the regularised default with its 95 % interval); the numerical halvings' paired
    shifts against the +-0.05 um tolerance; the CPU per run of every arm."""
    shifts = fc.paired_shifts(study)
    fig, (law, halving, cost) = plt.subplots(3, 1, figsize=(7.5, 10), gridspec_kw={"height_ratios": [3, 3, 2]})
    names = list(study.dataset.values)
    v_th = twin.load_parameters().value("pneumatics.friction_velocity_threshold") * 1e3
    for k, name in enumerate(names):
        cells = [shifts.sel(pairing=arm, dataset=name, feature="backlash_feature")
                 for arm in ("regularised_half_v_th", "elasto_plastic")]
        y = [0.0] + [float(c["mean"]) * 1e6 for c in cells]
        low = [0.0] + [(float(c["mean"]) - float(c.lower)) * 1e6 for c in cells]
        high = [0.0] + [(float(c.upper) - float(c["mean"])) * 1e6 for c in cells]
        x = np.arange(3) + 0.06 * (k - 1.5)
        law.errorbar(x, y, yerr=[low, high], fmt="o", capsize=3, color=f"C{k}", label=name)
        law.plot(x[:2], y[:2], "-", color=f"C{k}")   # a line along v_th only: the bristle law has none
    law.set_xticks(range(3), [f"regularised, v_th = {v_th:g} mm/s\n(the default)", f"regularised, {v_th / 2:g} mm/s",
                              "elasto-plastic\n(no v_th)"])
    law.axhline(0.0, color="0.5", lw=0.8)
    law.set_ylabel("f_b: paired shift from the default [um]\n(mean, 95 % interval)")
    law.legend(fontsize=8, ncol=4)
    law.grid(True, alpha=0.3)
    law.set_title(f"free-nut data sets, the thesis campaign's runs 0-{study.sizes['run'] - 1} (n per pairing: the "
                  "table),\nRK4 at the campaign step (62.5 us); the halvings at the same step or half of it",
                  fontsize=9)
    halvings = (("elasto_plastic_half_step", "elasto-plastic:\nstep halved"),
                ("elasto_plastic_half_step_half_guide_v_th", "guides:\nv_th halved"),
                ("regularised_half_v_th", "regularised:\nv_th halved"))
    for k, name in enumerate(names):
        for j, (pairing, _) in enumerate(halvings):
            c = shifts.sel(pairing=pairing, dataset=name, feature="backlash_feature")
            m = float(c["mean"]) * 1e6
            halving.errorbar(j + 0.1 * (k - 1.5), m, yerr=[[m - float(c.lower) * 1e6], [float(c.upper) * 1e6 - m]],
                             fmt="o", capsize=3, color=f"C{k}", label=name if j == 0 else None)
    tolerance = MEAN_SHIFT_TOLERANCE * 1e6
    halving.axhspan(-tolerance, tolerance, color="0.85", label="+-0.05 um")
    halving.set_xticks(range(len(halvings)), [label for _, label in halvings])
    halving.set_ylabel("f_b: paired shift when halved [um]")
    halving.legend(fontsize=8, ncol=5)
    halving.grid(True, alpha=0.3)
    arms = list(study.arm.values)
    cpu = [float(study.cpu_per_run.sel(arm=a).mean()) for a in arms]
    cost.barh(range(len(arms)), cpu, color="0.5")
    cost.set_yticks(range(len(arms)), [a.replace("_", " ") for a in arms], fontsize=7)
    cost.set_xlabel("CPU per 10 s run [s] (8 lanes, mean over the data sets)")
    cost.grid(True, axis="x", alpha=0.3)
    fig.tight_layout()
    for suffix in (".png", ".svg"):
        fig.savefig(path.with_suffix(suffix), dpi=100, metadata={"Date": None} if suffix == ".svg" else None)
    plt.close(fig)


def free_nut(out: Path) -> None:
    """Item 4: the free-nut traces' figures as a table, and their chart (the limit cycle on ds2, the contact
    oscillation on ds4)."""
    rows, traces = fc.free_nut_study(progress=lambda line: print(line, flush=True))
    print("\n| trace | nut - screw at rest, p-p [um] | period [ms] | force error at rest, rms / p-p [N] | "
          "piston speed at rest [mm/s rms] | contact oscillation, rms [N] / p-p [N] / Hz / at [s] | f_b [um] | "
          "H [um] | CPU [s] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['label']} | {r['rest_nut_peak_to_peak'] * 1e6:.1f} | {r['rest_period'] * 1e3:.0f} | "
              f"{r['rest_force_error_rms']:.0f} / {r['rest_force_error_peak_to_peak']:.0f} | "
              f"{r['rest_piston_speed_rms'] * 1e3:.2f} | {r['contact_rms']:.0f} / {r['contact_peak_to_peak']:.0f} / "
              f"{r['contact_frequency']:.0f} / {r['contact_start']:.1f} | {r['backlash_feature'] * 1e6:.3f} | "
              f"{r['backlash_hysteresis'] * 1e6:.3f} | {r['cpu_s']:.1f} |")
    fig, axes = plt.subplots(4, 2, figsize=(12, 10), sharex="col")
    panels = (("ds2 elasto_plastic 31.25 us, quiet", "ds2 elasto_plastic 15.625 us, quiet",
               "ds2 regularised 31.25 us, quiet"),
              ("ds4 elasto_plastic 15.625 us", "ds4 regularised 15.625 us",
               "ds4 regularised 15.625 us, friction_static = 250"))
    windows = ((5.8, 6.2), (6.6, 7.8))
    for col, (labels, (a, b)) in enumerate(zip(panels, windows, strict=True)):
        for k, label in enumerate(labels):
            trace = traces[label]
            t = trace.time.values
            w = (t > a) & (t < b)
            speed = np.gradient(trace.piston_position.values, t[1] - t[0])
            style = {"color": f"C{k}", "lw": 0.8, "label": label}
            axes[0, col].plot(t[w], (trace.nut1_position - trace.screw_equivalent_position).values[w] * 1e6, **style)
            axes[1, col].plot(t[w], speed[w] * 1e3, **style)
            axes[2, col].plot(t[w], (trace.external_force - trace.force_demand).values[w], **style)
            axes[3, col].plot(t[w], trace.nut1_contact_force.values[w], **style)
        axes[0, col].legend(fontsize=7, loc="upper right")
        axes[1, col].set_ylim(-8, 8)
        axes[3, col].set_xlabel("time [s]")
    axes[0, 0].set_title("ds2, no load-cell noise, the screw at rest: the loop's limit cycle", fontsize=9)
    axes[0, 1].set_title("ds4 with the load-cell noise: the contact oscillation", fontsize=9)
    for row, name in enumerate(("nut - screw [um]", "piston speed [mm/s]", "force error [N]", "nut contact force [N]")):
        axes[row, 0].set_ylabel(name)
    fig.tight_layout()
    for suffix in (".png", ".svg"):
        fig.savefig((out / "free_nut").with_suffix(suffix), dpi=100, metadata={"Date": None} if suffix == ".svg"
                    else None)
    plt.close(fig)


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
    parser.add_argument("--save-combined", metavar="FILE",
                        help="with --acceptance: write the folder's combined study to FILE (name it "
                             f"{ACCEPTANCE_PREFIX}*.nc to --replot it from its own folder)")
    parser.add_argument("--arms", help="with --acceptance: only these arms (comma-separated names)")
    parser.add_argument("--datasets", help="with --acceptance: only these data sets (comma-separated)")
    parser.add_argument("--free-nut", action="store_true",
                        help="the free-nut traces of issue 41 item 4 (app.studies.friction_convergence."
                             "FREE_NUT_CASES): their table and OUT/free_nut.png")
    parser.add_argument("--acceptance", metavar="START:STOP", nargs="?", const="",
                        help="the paired acceptance study instead of the sweep: the thesis campaign's runs START to "
                             "STOP-1 of ds2, ds4, ds6, ds7 under every arm (app.studies.friction_convergence."
                             "acceptance_arms); a later range adds to the same --out; with --replot and no range, "
                             "the table and chart of the folder's study")
    args = parser.parse_args()
    if args.out is None and not args.quick:
        parser.error("--out is required (the folder of the csv and the chart), except with --quick")
    out = Path(args.out) if args.out is not None else Path(tempfile.mkdtemp(prefix="friction_convergence_"))
    if args.free_nut:
        out.mkdir(parents=True, exist_ok=True)
        header("the free nut under the elasto-plastic seal: hold, creep or hunt (traces)", False)
        free_nut(out)
        return
    if args.acceptance is not None:
        if not args.replot and not args.acceptance:
            parser.error("--acceptance needs START:STOP (or --replot to redraw a folder's study)")
        out.mkdir(parents=True, exist_ok=True)
        header("friction law acceptance: paired halvings on the free-nut data sets", False)
        if not args.replot:
            start, stop = (int(x) for x in args.acceptance.split(":"))
            run_acceptance(out, range(start, stop), args.arms.split(",") if args.arms else None,
                           args.datasets.split(",") if args.datasets else None)
        study = read_acceptance(out)
        if args.save_combined:
            write_acceptance(study, Path(args.save_combined))
        acceptance_table(study)
        if {a.name for a in fc.acceptance_arms(twin.load_parameters())} <= set(study.arm.values):
            acceptance_chart(study, out / "friction_acceptance.png")
        else:
            print("\n(no chart: the folder does not hold every arm; --replot a folder that does)")
        return
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
