"""``twin`` command line: a thin layer over the library (the library never imports this module).

Each subcommand imports the campaign runner, the reports or the studies inside its handler
(lazy: start-up cost; `twin scenes` and `twin --help` must not load dask, scipy or matplotlib).
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from pathlib import Path

import twin
from app.service.command import add_serve_parser
from twin.engine.integrators import INTEGRATORS
from twin.errors import InputError, SimulationFailed
from twin.scenes import split_targets
from twin.solver import DEFAULT_SOLVER, ENGINES, solver_label


def _parse_assignment(text: str) -> tuple[str, float | str]:
    """``name=number`` in SI; else the text as it stands: a value with its unit (``scene.backlash="20 um"``,
    ``reducer.backlash="3 mrad"``), which the parameter set or the scene converts to its SI unit, or a scene
    condition's word (``scene.zero_procedure=preloaded``), which the scene checks against its allowed values."""
    name, sep, value = text.partition("=")
    if not sep or not name.strip() or not value.strip():
        raise argparse.ArgumentTypeError(f"--set expects name=value, got {text!r}")
    try:
        return name.strip(), float(value)
    except ValueError:
        return name.strip(), value.strip()


def _parse_fidelity(text: str) -> str | dict[str, str]:
    """``auto``, ``full`` or ``subsystem=level,...`` (``default=full`` sets the others)."""
    if "=" not in text:
        return text
    choices = {}
    for item in text.split(","):
        name, sep, level = item.partition("=")
        if not sep or not name.strip() or not level.strip():
            raise argparse.ArgumentTypeError(f"--fidelity expects auto, full or subsystem=level,..., got {text!r}")
        choices[name.strip()] = level.strip()
    return choices


def _parse_outputs(text: str) -> list[str]:
    return [name.strip() for name in text.split(",") if name.strip()]


def _scene_and_params(args) -> tuple[twin.Scene, twin.ParameterSet]:
    """Apply ``--set`` overrides: ``scene.<condition>=v`` to the scene, anything else to the parameters."""
    overrides = dict(args.set or [])
    conditions, parameters = split_targets(overrides)
    problems: list[str] = []
    scene = params = None
    try:
        scene = twin.load_scene(args.scene).with_conditions(conditions)
    except InputError as exc:
        problems += exc.problems
    try:
        nominal = twin.load_parameters(args.params)
        params = nominal.with_values(parameters)
    except InputError as exc:
        problems += exc.problems
    if problems:
        raise InputError("input", problems)
    _warn(nominal.implausible(parameters))  # before the run: a slip found now costs nothing
    return scene, params


def _warn(lines) -> None:
    for line in lines:
        print(f"twin: warning: {line}", file=sys.stderr)


def cmd_scenes(args) -> int:
    for name in twin.list_scenes():
        scene = twin.load_scene(name)
        print(f"{name:10s} {scene.duration:6.1f} s  {scene.description}")
    return 0


#: The ``twin simulate`` options that are fields of :class:`twin.Solver`: one given makes the run's solver, one left
#: out (``None``) takes the object's default, so the defaults have one home.
SOLVER_OPTIONS = ("integrator", "dt", "engine")


def _solver(args) -> twin.Solver:
    """The run's solver from the command line (checked when it is made: an :class:`twin.OptionError`)."""
    return twin.Solver(**{name: getattr(args, name) for name in SOLVER_OPTIONS if getattr(args, name) is not None})


def _check_bounds(**values) -> None:
    """The command line's numbers against the campaign spec's physical bounds (:data:`campaigns.runner.spec.BOUNDS`),
    every problem at once, before any work."""
    from campaigns.runner.spec import in_range

    problems = []
    for option, value in values.items():
        try:
            in_range(option, value)
        except ValueError as exc:
            problems.append(f"--{option.replace('_', '-')}: {exc}")
    if problems:
        raise InputError("command line", problems)


def _what_the_feature_is(ds) -> str:
    """One line under the printed Eq. 9.12 feature: what the number is, so that 30 um for an 80 um backlash reads
    right (a mean of a position difference, whose reading on a flank depends on the zero procedure: twin.features)."""
    import json

    b = json.loads(ds.attrs["scene_conditions"])["backlash"] * 1e6
    if b == 0:
        return ("(the mean over the test of |nut - screw equivalent position|; the scene has no backlash: it reads "
                "the elastic deflection between the screw and the nut and, measured, the encoders' errors)")
    on_a_flank = {"thesis": f"zeroed with the nuts centred in the gap, a nut held on a flank reads b/2 = {b / 2:g} um "
                            "and one crossing the gap less",
                  "preloaded": f"zeroed where the preloaded nuts rest, a nut that stays there reads 0 um and one "
                               f"pushed across the gap up to b = {b:g} um"}.get(
        ds.attrs["zero_procedure"], f"zero procedure {ds.attrs['zero_procedure']}")
    return (f"(the mean over the test of |nut - screw equivalent position|, not the gap; the scene's backlash b is "
            f"{b:g} um; {on_a_flank})")


def cmd_simulate(args) -> int:
    from campaigns.runner.files import check_output, write_netcdf

    _check_bounds(dt=args.dt, duration=args.duration)
    solver = _solver(args)
    for path in (args.out, args.plot):  # before the run: a refused file costs nothing
        if path is not None:
            check_output(path, force=args.force)
    scene, params = _scene_and_params(args)
    if args.duration is not None:
        scene = scene.with_duration(args.duration)
    if args.explain_fidelity:
        from twin.fidelity import resolve_fidelity
        from twin.scenes import CYLINDER_STATES, ZERO_PROCEDURES

        print(f"test procedure of scene {scene.name}:")
        print(
            f"  zero_procedure = {scene.condition('zero_procedure')}: "
            f"{ZERO_PROCEDURES[scene.condition('zero_procedure')]}")
        print(f"  cylinder = {scene.condition('cylinder')}: {CYLINDER_STATES[scene.condition('cylinder')]}")
        print(f"fidelity of scene {scene.name}:")
        print(resolve_fidelity(scene, params, args.fidelity, args.outputs).explain())
    ds = twin.simulate(scene, params, solver=solver, fidelity=args.fidelity, outputs=args.outputs, rng=args.seed,
                       throw=False)
    print(f"scene {scene.name}: status {ds.attrs['status']}"
          + (f" ({ds.attrs['failure_reason']} at t = {ds.attrs['t_reached']:.4g} s)" if ds.attrs["status"] != "ok"
             else "")
          + f", wall time {ds.attrs['wall_time']:.3f} s")
    print(f"test procedure: zero_procedure = {ds.attrs['zero_procedure']}, cylinder = {ds.attrs['cylinder']}")
    for name, label in (("backlash_feature", "backlash feature (Eq. 9.12)"),
                        ("backlash_hysteresis", "backlash hysteresis (zero-independent)")):
        if name in ds:
            print(
                f"{label}: measured {float(ds[name]) * 1e6:.4f} um, "
                f"true signals {float(ds[name + '_true']) * 1e6:.4f} um")
            if name == "backlash_feature":
                print(f"  {_what_the_feature_is(ds)}")
    print(f"fidelity: {ds.attrs['fidelity']} ({ds.attrs['integrated_states']} integrated states)")
    print(f"integrator: {solver_label(ds.attrs['integrator'], ds.attrs['dt'])}")
    if args.out:
        write_netcdf(ds, args.out, title=f"BenchTwin run of scene {scene.name}",
                     history=getattr(args, "command_line", f"twin simulate {scene.name}"))
        print(f"wrote {args.out}")
    if args.plot:
        from twin.plotting import plot_run

        plot_run(ds, args.plot)
        print(f"wrote {args.plot}")
    return 0 if ds.attrs["status"] == "ok" else 1


#: What ``twin accuracy`` writes in its --out directory (the charts with their .svg twins).
ACCURACY_DATA = ("work_precision.nc", "work_precision.csv", "control_baseline.csv", "stability.nc")
ACCURACY_CHARTS = ("work_precision.png", "work_precision.svg", "stability.png", "stability.svg",
                   "campaign_accuracy.png", "campaign_accuracy.svg")
#: What ``twin chapter5`` writes in its --out directory.
CHAPTER5_FILES = ("chapter5.json", "fig5_*.png", "fig7_*.png")


def cmd_accuracy(args) -> int:
    from app.studies.accuracy import replot, run_accuracy
    from campaigns.runner.files import check_outputs

    _check_bounds(duration=args.duration)
    # --replot asks for the charts to be redrawn: it replaces them (and only them) without --force
    check_outputs(args.out, ACCURACY_CHARTS, force=args.force or args.replot)
    if not args.replot:
        check_outputs(args.out, ACCURACY_DATA, force=args.force)
    if args.replot:
        paths = replot(args.out)
    else:
        paths = run_accuracy(args.out, args.scene, args.duration, quick=args.quick, stability=not args.no_stability,
                             campaign_runs=args.campaign_runs)
    for name, path in paths.items():
        print(f"wrote {name}: {path}")
    return 0


class Stages:
    """Announces each named stage of a long job as it starts, with the time elapsed so far."""

    def __init__(self):
        self.start = time.perf_counter()

    def __call__(self, stage: str, message: str) -> None:
        print(f"[{time.perf_counter() - self.start:6.0f} s] {stage}: {message}", flush=True)


def cmd_campaign_run(args) -> int:
    import campaigns
    from app.pipeline import run_campaign_pipeline
    from campaigns.runner.budget import estimate
    from campaigns.runner.files import CampaignInterrupted

    _check_bounds(workers=args.workers)
    if args.engine is not None:
        twin.Solver(engine=args.engine)  # an engine that cannot run here is refused before the spec is read
    spec = _with_engine(campaigns.load_spec(args.spec, runs=args.runs, timeout=args.timeout), args.engine)
    _warn(spec.warnings)
    out = args.out or Path("out") / spec.name
    print(f"campaign {spec.name}: {estimate(spec, workers=args.workers, run_function=_bench_run()).describe()}")
    announce = Stages()

    def wrote(kind: str, path: Path) -> None:
        if kind == "analysis":
            _print_analysis(path)
        else:
            print(f"wrote {kind} report: {path.resolve()}" if kind in ("html", "pdf") else f"wrote {path}")

    try:
        run_campaign_pipeline(spec, out, analyze=args.analyze, report=args.report, workers=args.workers,
                              scheduler=args.scheduler, resume=args.resume, allow_version_mix=args.allow_version_mix,
                              announce=announce, wrote=wrote)
    except CampaignInterrupted as stop:
        print(f"\ntwin: stopped by {stop.signal_name}: {stop.kept} of {stop.total} runs kept in {out}; resume with: "
              f"{resume_command(args, out)}", file=sys.stderr)
        return 143 if stop.signal_name == "SIGTERM" else 130
    announce("done", f"total {time.perf_counter() - announce.start:.0f} s")
    return 0


def _with_engine(spec, engine: str | None):
    """The spec with its ``[solver]`` table's ``engine`` replaced by ``--engine`` (validated as the spec's own)."""
    if engine is None:
        return spec
    from pydantic import ValidationError

    try:
        solver = type(spec.solver).model_validate({**spec.solver.model_dump(), "engine": engine})
    except ValidationError as exc:
        raise InputError("command line", [f"--engine: {error['msg']}" for error in exc.errors()]) from None
    return spec.model_copy(update={"solver": solver})


def resume_command(args, out: Path) -> str:
    """The ``twin campaign run`` command that resumes this one: the same spec and options, plus ``--resume``."""
    words = ["twin", "campaign", "run", str(args.spec), "--out", str(out)]
    for option, value in (("--runs", args.runs), ("--timeout", args.timeout), ("--scheduler", args.scheduler),
                          ("--engine", args.engine)):
        if value is not None:
            words += [option, f"{value:g}" if isinstance(value, float) else str(value)]
    if args.workers != 2:
        words += ["--workers", str(args.workers)]
    words += [flag for flag, on in (("--analyze", args.analyze), ("--report", args.report),
                                    ("--allow-version-mix", args.allow_version_mix)) if on]
    return shlex.join([*words, "--resume"])


def _bench_run():
    from campaigns.bench.adapter import simulate_run

    return simulate_run


def _print_analysis(path: Path) -> None:
    """Name the analysis file, then print its verdict statements (stdout) and insufficient-data warnings (stderr)."""
    import xarray as xr

    from campaigns.analysis.campaign_analysis import summary
    from campaigns.analysis.margins import statements as margin_statements

    print(f"wrote {path}")
    with xr.open_dataset(path, engine="netcdf4") as handle:
        analysis = handle.load()
    statements, warnings = summary(analysis)
    control = margin_statements(analysis)
    for line in statements:
        print(line)
    for feature, verdict, reason in (_undecided(analysis) if statements else []):
        print(f"  {feature} ({verdict}): {reason}")
    if control:
        print("control robustness (loop margins of every run against the design limits):")
    for line in control:
        print(f"  {line}")
    _print_model_form(path.parent)
    for line in warnings:
        print(f"warning: {line}", file=sys.stderr)


def _print_model_form(folder: Path) -> None:
    """A model-form study's table beside the analysis: its headline, then each variant's requirement verdict per
    feature with the detection probability's shift at the requirement and whether it changes the verdict."""
    import xarray as xr

    from campaigns.analysis.model_form import FILE_NAME, variant_lines

    path = folder / FILE_NAME
    if not path.is_file():
        return
    with xr.open_dataset(path, engine="netcdf4") as handle:
        table = handle.load()
    print(f"wrote {path}")
    print(f"model form: {table.attrs['headline']}")
    for line in variant_lines(table):
        print(f"  {line}")


def _undecided(analysis) -> list[tuple[str, str, str]]:
    """``(feature, verdict, how many runs would decide it)`` of each verdict the runs left open (analysis.nc's
    ``runs_to_decide_reason``)."""
    if "runs_to_decide_reason" not in analysis:
        return []
    return [(str(f), str(analysis["requirement_verdict"].sel(feature=f).item()),
             str(analysis["runs_to_decide_reason"].sel(feature=f).item())) for f in analysis["feature"].values
            if str(analysis["requirement_verdict"].sel(feature=f).item()) in ("undetermined", "insufficient data")]


def cmd_campaign_analyze(args) -> int:
    import campaigns
    from campaigns.analysis.model_form import FILE_NAME as MODEL_FORM_FILE
    from campaigns.analysis.model_form import is_model_form
    from campaigns.runner.storage import check_output, read_results

    out = check_output(args.out or args.results.with_name("analysis.nc"), [args.results], force=args.force,
                       product="analysis.nc")
    results = read_results(args.results)  # a truncated or foreign file: one message naming it, before any work
    if is_model_form(results):  # its table is written beside the analysis: the same rule for it
        check_output(out.with_name(MODEL_FORM_FILE), [args.results], force=args.force)
    _print_analysis(campaigns.analyze(args.results, out))
    return 0


def _results_and_analysis(path: Path):
    """A campaign's results and, when it is beside them, its analysis (None otherwise)."""
    from campaigns.runner.storage import read_analysis, read_results

    results = read_results(path)
    analysis_path = path.with_name("analysis.nc")
    if not analysis_path.is_file():
        return results, None
    analysis = read_analysis(analysis_path, path)
    return results, analysis if analysis.attrs.get("source_spec_hash") == results.attrs.get("spec_hash") else None


def _nominal_text(parameters: str, target: str) -> str | None:
    """A parameter's nominal value in the parameter set ``parameters`` as a spec states it (SI, with its unit), or
    None when the set or the parameter is unknown (a spec difference then reads "the parameter set's nominal")."""
    try:
        parameter = twin.load_parameters(parameters)[target]
    except (InputError, KeyError, OSError):
        return None
    unit = "" if parameter.unit in ("", "1") else f" {parameter.unit}"
    return f"{parameter.value:g}{unit} (nominal)"


def cmd_campaign_compare(args) -> int:
    from campaigns.workflows.design_comparison import MIN_RUNS, compare, describe_shift, failure_text

    candidate, candidate_analysis = _results_and_analysis(args.a)
    baseline, baseline_analysis = _results_and_analysis(args.b)
    found = compare(baseline, candidate, baseline_analysis, candidate_analysis, nominal=_nominal_text)
    print(f"{found.name_b} ({args.a}) against {found.name_a} ({args.b}): differences {found.name_b} - {found.name_a}")
    print(f"pairing: {'paired' if found.paired else 'unpaired'}: {found.pairing}")
    print(f"design changes ({found.name_a} → {found.name_b}):" + (
        "" if found.spec_changes else " none: the two specs differ in name and description only"))
    for change in found.spec_changes:
        print(f"  {change}")
    if failures := failure_text(found, detail=True):
        print(failures)
    for shift in found.shifts:
        print(f"  {shift.dataset} {shift.feature}: mean shift {describe_shift(shift.mean, shift.unit)}; sd shift "
              f"{describe_shift(shift.sd, shift.unit)}; n = {shift.n_b}/{shift.n_a}"
              + (" (resolved)" if shift.mean.resolved else "" if shift.made else
                 f" (could not be made: fewer than {MIN_RUNS} runs ok)"))
    if not found.verdicts:
        print("verdicts: not compared (an analysis.nc is missing beside the results; `twin campaign analyze` both)")
    for change in found.verdicts:
        print(f"  {change.what}: {change.verdict_b} ({found.name_b}) / {change.verdict_a} ({found.name_a})"
              + (" CHANGED" if change.changed else ""))
    print(found.sentence)
    return 0


def cmd_campaign_replay(args) -> int:
    from campaigns.bench.replay import replay_run

    run = replay_run(args.results, args.dataset, args.run, out=args.out, force=args.force)
    print(f"replayed run {args.run} of data set {args.dataset}: status {run.attrs['status']} "
          f"(stored: {run.attrs['stored_status']}), {run.sizes.get('time', 0)} time samples")
    identical = True
    for feature in [v for v in run.data_vars if f"identical_{v}" in run.attrs]:
        same = run.attrs[f"identical_{feature}"] == "yes"
        identical &= same
        print(f"  {feature}: replayed {float(run[feature]):.17g}, stored {run.attrs[f'stored_{feature}']:.17g} "
              f"[{run[feature].attrs.get('units', '')}] -> {'bit-identical' if same else 'DIFFERENT'}")
    if args.out:
        print(f"wrote {args.out}")
    return 0 if identical else 1


def cmd_campaign_bracket(args) -> int:
    import campaigns
    from campaigns.runner.storage import CampaignError
    from campaigns.workflows.level_search import Settings, search, statement, store

    settings = Settings.checked(feature=args.feature, resolution=args.resolution, method=args.method,
                                max_levels=args.max_levels, stages=args.stages or [], runs=args.budget)
    out = args.out or Path("out") / campaigns.load_spec(args.spec).name
    if (out / "spec.json").exists():  # refused before the search's runs, not after them
        raise CampaignError(f"{out}: holds a campaign already; a bracket search writes a new one: choose another --out")
    result = search(args.spec, settings, runs=args.runs, progress=print)
    print(statement(result))
    path = store(result, out)
    print(f"wrote {path}")
    _print_analysis(path.with_name("analysis.nc"))
    return 0


def cmd_fidelity_levels(args) -> int:
    from twin.fidelity import SUBSYSTEMS

    for subsystem in SUBSYSTEMS.values():
        print(f"{subsystem.name}: {subsystem.description}")
        for level in subsystem.levels:
            removed = f" [removes {len(level.removes_states)} states]" if level.removes_states else ""
            print(f"    {level.name:15s} {level.description}{removed}")
    return 0


def cmd_fidelity_audit(args) -> int:
    from campaigns.bench.scene_audit import audit_scene

    result = audit_scene(args.scene, args.out or Path("out") / f"fidelity_audit_{Path(args.scene).stem}",
                         runs=args.runs, spec_path=args.spec, workers=args.workers)
    print(result.attrs["fidelity_auto"])
    for line in result.attrs["summary"].splitlines():
        print(line)
    return 0


def cmd_report(args) -> int:
    from campaigns.runner.storage import CampaignError, check_output
    from reports import build_report

    if args.out.exists() and not args.out.is_dir():
        raise CampaignError(f"{args.out} is not a directory; --out names the directory for report.html and report.pdf")
    for name in ("report.html", "report.pdf"):
        check_output(args.out / name, [args.results, args.analysis, args.accuracy, args.against, *args.measured],
                     force=args.force)
    for kind, path in build_report(args.results, args.analysis, args.out, accuracy_path=args.accuracy,
                                   measured_paths=args.measured, against_path=args.against).items():
        print(f"wrote {kind} report: {path}")
    return 0


def cmd_measure_import(args) -> int:
    from campaigns.runner.files import check_output, write_netcdf
    from campaigns.units import quantity
    from campaigns.workflows.measured import import_measured, load_mapping

    out = args.out or args.file.with_name(f"{args.file.stem}_measured.nc")
    check_output(out, [args.file, args.mapping], force=args.force)
    test = import_measured(args.file, load_mapping(args.mapping))
    channels = ", ".join(v for v in test.data_vars if "time" in test[v].dims)
    print(f"measured test {test.attrs['measured_test']}: {test.attrs['samples']} acquisition instants "
          f"({test.attrs['acquisition_period'] * 1e3:g} ms), channels {channels}")
    for name in (v for v in test.data_vars if test[v].attrs.get("role") == "feature"):
        value, unit = float(test[name]), test[name].attrs["units"]
        print(f"  {name}: {quantity(value, unit, 4)}")
    write_netcdf(test, out, title=test.attrs["title"], history=args.command_line)
    print(f"wrote {out}")
    return 0


def cmd_measure_diagnose(args) -> int:
    from campaigns.runner.storage import read_results
    from campaigns.units import quantity
    from campaigns.workflows.diagnosis import describe, diagnose
    from campaigns.workflows.measured import read_measured

    test = read_measured(args.test)
    try:
        found = diagnose(test, read_results(args.campaign))
    except ValueError as exc:  # nothing in common between the test and the campaign
        raise InputError("measured test", [f"{args.test}: {exc}"]) from None
    print(f"measured test {found.test} against {args.campaign}:")
    for feature in found.features:
        unit = test[feature].attrs.get("units", "")
        print(f"{feature} = {quantity(float(test[feature]), unit, 4)}")
        for placement in found.placements[feature]:
            print(f"  {placement.dataset}: {describe(placement, unit)}")
        if found.fault.get(feature) is not None:
            print(f"  fault size: {found.fault[feature].statement}")
    for note in found.notes:
        print(f"note: {note}")
    print(f"verdict: {found.verdict}")
    return 0


def cmd_export(args) -> int:
    from campaigns.runner.files import check_outputs
    from campaigns.runner.storage import read_analysis, read_results
    from campaigns.workflows.export import export, file_names, tables

    results = read_results(args.results)
    analysis_path = args.analysis or args.results.with_name("analysis.nc")
    analysis = None
    if analysis_path.is_file():
        analysis = read_analysis(analysis_path, args.results)
        if analysis.attrs.get("source_spec_hash") != results.attrs.get("spec_hash"):
            raise InputError("export", [f"{analysis_path}: the analysis of another campaign (its source_spec_hash "
                                        "differs from the results' spec_hash); re-run `twin campaign analyze`"])
    elif args.analysis is not None:
        raise FileNotFoundError(f"{args.analysis}: no such file")
    frames = tables(results, analysis)
    out = args.out or args.results.parent / "export"
    check_outputs(out, file_names(args.format, frames), force=args.force)
    for path in export(frames, args.format, out, campaign=str(results.attrs.get("campaign", ""))):
        print(f"wrote {path}")
    print(f"tables: {', '.join(f'{name} ({len(frame)} rows)' for name, frame in frames.items())}")
    if analysis is None:
        print(f"note: no analysis.nc beside {args.results}: only the runs table; `twin campaign analyze` first for "
              "the analysis tables", file=sys.stderr)
    return 0


#: Files a procedure search writes in its --out (besides its candidates' campaigns under candidates/).
SEARCH_FILES = ("search.nc", "ranking.csv", "search_report.html", "search_report.pdf", "pareto.png")


def cmd_procedure_search(args) -> int:
    from campaigns.runner.files import check_outputs
    from campaigns.runner.storage import CampaignError
    from campaigns.workflows.procedure_search import describe_plan, design, load_search, run_search, test_duration

    _check_bounds(workers=args.workers)
    spec = load_search(args.spec, quick=args.quick)
    out = args.out or Path("out") / spec.name
    print(f"procedure search {spec.name}: {describe_plan(spec)}")
    for candidate in design(spec):
        knobs = ", ".join(f"{k} {v:g}" if isinstance(v, (int, float)) else f"{k} {v}"
                          for k, v in candidate.shown.items())
        label = " (reference: the base scene's own procedure)" if candidate.reference else ""
        print(f"  {candidate.name}{label}: {knobs}; {test_duration(spec, candidate):.3g} s per test")
    if args.plan:
        return 0
    if not args.resume:
        check_outputs(out, SEARCH_FILES)
        if (out / "candidates").exists():
            raise CampaignError(f"{out / 'candidates'}: holds the campaigns of an earlier search; --resume continues "
                                "it (finished runs kept, the search's own files rewritten), a new --out starts another")
    announce = Stages()
    path = run_search(spec, out, workers=args.workers, resume=args.resume, announce=announce)
    print(f"wrote {path}\nwrote {path.parent / 'ranking.csv'}")
    import xarray as xr

    with xr.open_dataset(path, engine="netcdf4") as handle:
        print(handle.attrs["statement"])
    from reports import build_search_report  # lazy: figures and typst only when a report is written

    announce("report", "the ranked table, the Pareto chart, HTML and PDF")
    for kind, written in build_search_report(path, out).items():
        print(f"wrote {kind}: {written.resolve()}")
    announce("done", f"total {time.perf_counter() - announce.start:.0f} s")
    return 0


def cmd_chapter5(args) -> int:
    from app.studies.chapter5 import run_chapter5
    from campaigns.runner.files import check_outputs

    check_outputs(args.out, CHAPTER5_FILES, force=args.force)

    result = run_chapter5(args.out, dynamic=not args.no_dynamic)
    for path in result["figures"]:
        print(f"wrote {path}")
    for key, value in result["summary"].items():
        print(f"{key}: {value}")
    return 0


def _run_counts(text: str) -> list[int]:
    """``--stages 80,160,320``: runs per level at each look."""
    try:
        return [int(n) for n in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: runs per look as whole numbers separated by commas, "
                                         "e.g. 80,160,320") from None


def _add_simulate_parser(sub) -> None:
    """``twin simulate``."""
    p = sub.add_parser("simulate", help="run one scene and write its signals and/or a plot")
    p.add_argument("scene", help="built-in scene name (see `twin scenes`) or a scene TOML file")
    p.add_argument("--params", default="bench", help="parameter set name or directory/file (default: bench)")
    p.add_argument("--set", action="append", type=_parse_assignment, metavar="NAME=VALUE",
                   help="override a parameter (e.g. motor.inertia=1.6e-4, reducer.backlash='3 mrad') or a scene "
                        "condition (scene.backlash=2e-5 or '20 um', scene.zero_procedure=preloaded, "
                        "scene.cylinder=detached); a number alone is in SI units")
    p.add_argument("--integrator", choices=sorted(INTEGRATORS),
                   help=f"fixed-step method (default {DEFAULT_SOLVER.integrator}; twin.Solver, docs/accuracy.md)")
    p.add_argument("--dt", type=float, help="integration step [s] (default: the method's step at the run's "
                                            "fidelity, twin.Solver.step)")
    p.add_argument("--engine", choices=ENGINES, help=f"where the compiled loop runs (default {DEFAULT_SOLVER.engine}; "
                                                     "cuda: an NVIDIA GPU, docs/gpu.md)")
    p.add_argument("--duration", type=float, help="override the scene duration [s]")
    p.add_argument("--fidelity", type=_parse_fidelity, default="auto", metavar="auto|full|SUBSYSTEM=LEVEL,...",
                   help="subsystem fidelity (see `twin fidelity levels`; default auto: the cheapest the scene allows)")
    p.add_argument("--outputs", type=_parse_outputs, metavar="NAME,...",
                   help="signals and features the run must produce (default: the scene's outputs)")
    p.add_argument("--explain-fidelity", action="store_true", help="print each subsystem's level and why")
    p.add_argument("--seed", type=int, default=0, help="seed of the electrical noise")
    p.add_argument("--out", type=Path, help="write the run Dataset (netCDF)")
    p.add_argument("--plot", type=Path, help="write an overview plot (PNG/SVG/PDF)")
    p.add_argument("--force", action="store_true", help="replace an existing --out or --plot file "
                                                        "(never a campaign's own files)")
    p.set_defaults(func=cmd_simulate)


def _add_study_parsers(sub) -> None:
    """``twin accuracy`` and ``twin chapter5``: the solver and validation studies."""
    p = sub.add_parser("accuracy", help="speed-versus-accuracy study: work-precision chart, stability map, baselines")
    p.add_argument("--scene", default="nominal", help="scene of the study (default: nominal)")
    p.add_argument("--duration", type=float, default=1.5, help="simulated time of each run [s] (default 1.5)")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--quick", action="store_true", help="short ladders, single timing (a first look)")
    p.add_argument("--no-stability", action="store_true", help="skip the stability map")
    p.add_argument("--campaign-runs", type=int, default=0,
                   help="also compare candidate solvers over N sampled runs of data sets 2 and 5 (e.g. 100)")
    p.add_argument("--replot", action="store_true",
                   help="only redraw (replace) the charts from the data in --out")
    p.add_argument("--force", action="store_true", help="replace the files of an earlier study in --out")
    p.set_defaults(func=cmd_accuracy)

    p = sub.add_parser("chapter5", help="validation against the thesis's Ch. 5: Figs. 5.6-5.13 and 7.22 regenerated")
    p.add_argument("--out", type=Path, default=Path("out/chapter5"), help="output directory (default out/chapter5)")
    p.add_argument("--no-dynamic", action="store_true", help="skip the simulated hysteresis of Figs. 5.11-5.12")
    p.add_argument("--force", action="store_true", help="replace the figures of an earlier run in --out")
    p.set_defaults(func=cmd_chapter5)


def _add_campaign_parsers(sub) -> None:
    """``twin campaign run | analyze | compare | replay | bracket``."""
    campaign = sub.add_parser("campaign", help="Monte Carlo campaigns: run a spec, analyse its results")
    campaign_sub = campaign.add_subparsers(dest="campaign_command", required=True)
    p = campaign_sub.add_parser("run", help="run a campaign spec (TOML) on a local dask cluster or a scheduler")
    p.add_argument("spec", type=Path, help="campaign spec, e.g. campaigns/specs/demo.toml")
    p.add_argument("--runs", type=int, help="runs per data set (overrides the spec)")
    p.add_argument("--out", type=Path, help="output directory (default: out/<spec name>)")
    p.add_argument("--workers", type=int, default=2, help="local worker processes (default 2)")
    p.add_argument("--scheduler", help="address of an existing dask scheduler (instead of a local cluster)")
    p.add_argument("--resume", action="store_true", help="skip finished chunks of an interrupted run")
    p.add_argument("--timeout", type=float, help="wall-clock budget of one run [s] (overrides execution.timeout)")
    p.add_argument("--engine", choices=ENGINES, help="where the compiled loop runs (overrides solver.engine; cuda: "
                                                     "an NVIDIA GPU, one run per thread, docs/gpu.md)")
    p.add_argument("--allow-version-mix", action="store_true",
                   help="on --resume, accept chunks computed by another BenchTwin/numpy/numba/scipy version "
                        "or model code")
    p.add_argument("--analyze", action="store_true", help="also write analysis.nc")
    p.add_argument("--report", action="store_true", help="also write report.html and report.pdf")
    p.set_defaults(func=cmd_campaign_run)
    p = campaign_sub.add_parser("analyze", help="correlations, separation and observability of a results.nc")
    p.add_argument("results", type=Path, help="results.nc of a campaign")
    p.add_argument("--out", type=Path, help="analysis file (default: analysis.nc beside the results)")
    p.add_argument("--force", action="store_true", help="replace an existing analysis file")
    p.set_defaults(func=cmd_campaign_analyze)
    p = campaign_sub.add_parser("compare", help="design A against design B: paired where the seeds allow, the "
                                                "shift of every feature's distribution and every verdict")
    p.add_argument("a", type=Path, help="results.nc of design A (the candidate)")
    p.add_argument("b", type=Path, help="results.nc of design B (the baseline)")
    p.set_defaults(func=cmd_campaign_compare)
    p = campaign_sub.add_parser("replay", help="re-run one run of a campaign alone, with its full time series")
    p.add_argument("results", type=Path, help="results.nc of a campaign")
    p.add_argument("--dataset", required=True, help="data-set name, e.g. ds6")
    p.add_argument("--run", type=int, required=True, help="run index within the data set (zero-based)")
    p.add_argument("--out", type=Path, help="write the replayed run (netCDF)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file")
    p.set_defaults(func=cmd_campaign_replay)
    p = campaign_sub.add_parser("bracket", help="add levels to a spec's fault sweep until the minimum detectable size "
                                                "is bracketed to --resolution, the requirement tried first "
                                                "(docs/level_search.md); runs in this process")
    p.add_argument("spec", type=Path, help="campaign spec with an observability sweep, e.g. "
                                           "campaigns/specs/backlash_bracket.toml")
    p.add_argument("--feature", default="backlash_feature", help="feature searched (default backlash_feature)")
    p.add_argument("--resolution", type=float, help="widest gap of levels around the estimate and inside its "
                                                    "bounds [SI: m, or N for preload loss]; default: the "
                                                    "requirement level only")
    p.add_argument("--method", default="bisection", help="bisection (default) or monotone_fit")
    p.add_argument("--max-levels", type=int, default=8, help="levels the search may add (default 8)")
    p.add_argument("--stages", type=_run_counts,
                   help="runs per level at each look, e.g. 80,160,320 (Bonferroni over the looks)")
    p.add_argument("--budget", type=int, help="the most runs the search may execute")
    p.add_argument("--runs", type=int, help="runs per level (overrides the spec; without --stages)")
    p.add_argument("--out", type=Path, help="output directory (default: out/<spec name>)")
    p.set_defaults(func=cmd_campaign_bracket)


def _add_fidelity_parsers(sub) -> None:
    """``twin fidelity levels | audit``."""
    fidelity = sub.add_parser("fidelity", help="fidelity levels and the audit of the automatic choice")
    fidelity_sub = fidelity.add_subparsers(dest="fidelity_command", required=True)
    p = fidelity_sub.add_parser("levels", help="list every subsystem's fidelity levels")
    p.set_defaults(func=cmd_fidelity_levels)
    p = fidelity_sub.add_parser("audit", help="auto against full fidelity on the same sampled runs of a scene")
    p.add_argument("scene", help="built-in scene name or a scene TOML file")
    p.add_argument("--runs", type=int, default=50, help="sampled runs (default 50)")
    p.add_argument("--spec", type=Path,
                   help="campaign spec whose uncertainty table is sampled (default: the thesis study)")
    p.add_argument("--workers", type=int, default=2, help="local worker processes (default 2)")
    p.add_argument("--out", type=Path, help="output directory (default: out/fidelity_audit_<scene>)")
    p.set_defaults(func=cmd_fidelity_audit)


def _add_results_parsers(sub) -> None:
    """``twin report`` and ``twin export``: what is made from stored results."""
    p = sub.add_parser("report", help="HTML and PDF report of a campaign's stored results (no simulation)")
    p.add_argument("results", type=Path, help="results.nc of a campaign")
    p.add_argument("--analysis", type=Path, help="analysis.nc (default: beside the results, else computed in memory)")
    p.add_argument("--accuracy", type=Path, help="work_precision.nc of `twin accuracy` (speed-and-accuracy section)")
    p.add_argument("--measured", type=Path, nargs="+", default=[], metavar="TEST",
                   help="measured tests (`twin measure import`) placed in each data set and diagnosed")
    p.add_argument("--against", type=Path, metavar="OTHER_RESULTS",
                   help="another design's results.nc: a comparison report (this campaign against it)")
    p.add_argument("--out", type=Path, required=True, help="directory for report.html and report.pdf")
    p.add_argument("--force", action="store_true", help="replace an existing report in --out")
    p.set_defaults(func=cmd_report)

    p = sub.add_parser("export", help="a campaign's tables (one row per run; the analysis) as CSV, Excel or MATLAB")
    p.add_argument("results", type=Path, help="results.nc of a campaign")
    p.add_argument("--format", choices=("csv", "xlsx", "mat"), default="csv", help="file format (default csv)")
    p.add_argument("--analysis", type=Path, help="analysis.nc (default: beside the results, when there)")
    p.add_argument("--out", type=Path, help="directory to write into (default: export/ beside the results)")
    p.add_argument("--force", action="store_true", help="replace files of an earlier export in --out")
    p.set_defaults(func=cmd_export)


def _add_measure_parsers(sub) -> None:
    """``twin measure import | diagnose``."""
    measure = sub.add_parser("measure", help="measured tests: import a bench file, diagnose it against a campaign")
    measure_sub = measure.add_subparsers(dest="measure_command", required=True)
    p = measure_sub.add_parser("import", help="map a measured file's channels onto the twin's signals and compute "
                                              "its features with the twin's code")
    p.add_argument("file", type=Path, help="the measured test: CSV or netCDF")
    p.add_argument("--mapping", type=Path, required=True,
                   help="TOML mapping of the file's columns to the twin's signals, units and calibration "
                        "(docs/campaigns.md, Measured tests)")
    p.add_argument("--out", type=Path, help="the measured test to write (default: FILE's stem + _measured.nc)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file")
    p.set_defaults(func=cmd_measure_import)
    p = measure_sub.add_parser("diagnose", help="place a measured test against a campaign: percentile and "
                                                "consistency per data set, the fault size from the sweep")
    p.add_argument("test", type=Path, help="a measured test written by `twin measure import`")
    p.add_argument("--campaign", type=Path, required=True, help="results.nc of the campaign")
    p.set_defaults(func=cmd_measure_diagnose)


def _add_procedure_parsers(sub) -> None:
    """``twin procedure search``."""
    procedure = sub.add_parser("procedure", help="test procedures: search the knobs for the one that detects a fault "
                                                 "within one unit soonest")
    procedure_sub = procedure.add_subparsers(dest="procedure_command", required=True)
    p = procedure_sub.add_parser("search", help="coarse design, screening rounds and finalists' campaigns; ranked "
                                                "table, Pareto chart and report (campaigns/specs/procedure_*.toml)")
    p.add_argument("spec", type=Path, help="search spec (TOML)")
    p.add_argument("--out", type=Path, help="output directory (default: out/<search name>)")
    p.add_argument("--workers", type=int, default=2, help="worker processes of each campaign (default 2)")
    p.add_argument("--quick", action="store_true", help="a plan that still ranks: the reference and the anchors (or "
                                                        "3 candidates), 1 round, 1 finalist, the unit and repeat "
                                                        "floors")
    p.add_argument("--plan", action="store_true", help="print the plan and the candidates, run nothing")
    p.add_argument("--resume", action="store_true", help="continue an interrupted search in --out (finished runs "
                                                         "kept; the search's own files rewritten)")
    p.set_defaults(func=cmd_procedure_search)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="twin", description="BenchTwin: ball-screw test-bench digital twin")
    parser.add_argument("--version", action="version", version=f"%(prog)s {twin.__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("scenes", help="list the built-in scenes (test procedures)")
    p.set_defaults(func=cmd_scenes)
    for add in (_add_simulate_parser, _add_study_parsers, _add_campaign_parsers, _add_fidelity_parsers,
                _add_results_parsers, _add_measure_parsers, _add_procedure_parsers, add_serve_parser):
        add(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    args.command_line = shlex.join(["twin", *(sys.argv[1:] if argv is None else argv)])
    try:
        return args.func(args)
    except Exception as exc:
        if not isinstance(exc, _user_errors()):
            raise
        print(f"twin: error: {exc}", file=sys.stderr)
        return 2


def _user_errors() -> tuple[type[Exception], ...]:
    """Errors that are the user's to fix: reported in one message, without a traceback."""
    from campaigns.runner.storage import CampaignError
    from reports.errors import ReportError

    return InputError, SimulationFailed, CampaignError, ReportError, FileNotFoundError


if __name__ == "__main__":
    sys.exit(main())
