"""Mutation score of the test suite: how many deliberate bugs in a module set the unit tests catch.

Usage::

    .venv/bin/python benchmarks/mutation_score.py --quick            # CI: physics set, 40 sampled mutants
    .venv/bin/python benchmarks/mutation_score.py --sets physics sensors --sample 150
    .venv/bin/python benchmarks/mutation_score.py --sets analysis --all

Mutants come from cosmic-ray's operators (``cosmic_ray.mutating.mutate_code``), restricted to the
kinds of slip a physics code makes: arithmetic swaps (``+ -``, ``* /``), comparison swaps (``< <=``,
``> >=``, ``== !=``), a dropped or added negation, a changed number constant, ``and``/``or``,
``True``/``False``, ``break``/``continue`` and a loop that never runs. (Bit operators, ``%``, ``//``,
``is``, decorator removal and decorator arguments are left out: the code has no bit logic, and
``@njit`` or its ``cache=True`` make no difference when the tests run uncompiled.)

Why not cosmic-ray's own runner: it starts one test process per mutant, ~10 s here just to import
the stack; this script keeps one process per module set, with ``NUMBA_DISABLE_JIT=1`` so a
mutated numba function needs no recompilation, and for each mutant writes the mutated source into
a private copy of the repository, drops the project's modules from ``sys.modules`` and runs
``pytest.main`` on the unit tests that cover the module (``TESTS``), stopping at the first
failure. A mutant is *killed* when a test fails or errors (a mutant that breaks the import
counts too, as cosmic-ray's "incompetent"), or runs past ``--timeout`` (SIGALRM); it *survives*
when the tests pass. Score = killed / tested. With ``--sample N`` a fixed-seed random sample of N
mutants per set is tested and the score comes with a 95 % Wilson interval.

The copy lives in a temporary directory, so an interrupted run never leaves a mutant behind in
the working tree.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import os
import random
import re
import shutil
import signal
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
COPIED = ("app", "twin", "sensors", "numerics", "campaigns", "reports", "tests", "docs", "pyproject.toml")
PROJECT_PACKAGES = ("app", "twin", "sensors", "numerics", "campaigns", "reports")

_ANALYSIS_TESTS = ["tests/campaigns/test_analysis_known_answers.py", "tests/campaigns/test_campaign_analysis.py",
                   "tests/campaigns/test_campaign_verdict.py", "tests/campaigns/test_campaign_sensitivity.py",
                   "-k", "not synthetic_campaign and not cli_prints"]
#: Module -> unit tests that exercise it without running the full compiled loop.
# the tangents of the stiff elements (the linearly implicit integrator's) are tested against finite differences there
_CONTACT_TANGENT = "tests/engine/test_imex_euler.py::test_contact_tangent_matches_finite_differences"
_SLOPES = "tests/engine/test_imex_euler.py::test_friction_slopes_match_finite_differences"
TESTS = {
    "twin/physics/ball_groove_friction.py": ["tests/physics/test_ball_groove_friction.py", _SLOPES],
    "twin/physics/ball_screw.py": ["tests/physics/test_ball_screw.py", "tests/physics/test_lead_error.py",
                                   _CONTACT_TANGENT],
    "twin/physics/coupling.py": ["tests/physics/test_components.py"],
    "twin/physics/friction.py": ["tests/physics/test_components.py", _SLOPES],
    "twin/physics/groove.py": ["tests/physics/test_groove.py", "tests/physics/test_hertz.py"],
    "twin/physics/hertz.py": ["tests/physics/test_hertz.py"],
    "twin/physics/motor.py": ["tests/physics/test_components.py"],
    "twin/physics/pneumatics.py": ["tests/physics/test_pneumatics.py"],
    "twin/physics/preload.py": ["tests/physics/test_components.py"],
    "sensors/acquisition.py": ["tests/sensors/test_sensor_acquisition.py", "tests/sensors/test_sensor_force_torque.py",
                               "tests/sensors/test_sensor_compiled_loop.py"],
    "sensors/analog.py": ["tests/sensors/test_sensor_force_torque.py", "tests/sensors/test_sensor_compiled_loop.py"],
    "sensors/encoder.py": ["tests/sensors/test_sensor_encoder.py", "tests/sensors/test_sensor_encoder_speed.py",
                           "tests/sensors/test_sensor_encoder_timing.py", "tests/sensors/test_sensor_lanes.py",
                           "tests/sensors/test_sensor_compiled_loop.py"],
    "sensors/load_cell.py": ["tests/sensors/test_sensor_force_torque.py"],
    "sensors/parameters.py": ["tests/sensors/test_sensor_parameters.py"],
    "sensors/resolver.py": ["tests/sensors/test_sensor_resolver.py", "tests/sensors/test_sensor_compiled_loop.py"],
    "sensors/torque_meter.py": ["tests/sensors/test_sensor_force_torque.py"],
    # the statistics' unit tests; not the end-to-end synthetic campaign (a dask campaign per mutant: minutes) nor
    # the CLI test (a subprocess imports the installed package, not the mutated copy)
    "campaigns/statistics/detection.py": _ANALYSIS_TESTS,
    "campaigns/statistics/sensitivity.py": _ANALYSIS_TESTS,
    # the verdict code of the report: known answers on in-memory analyses (no PDF, no campaign)
    "reports/sections/executive.py": ["tests/reports/test_report_verdicts.py"],
    "reports/builder.py": ["tests/reports/test_report_verdicts.py"],
    "reports/inputs.py": ["tests/reports/test_report_verdicts.py"],  # not test_report_inputs: a campaign per mutant
}
#: Modules of which only some functions (or methods) are mutated: the report's verdict code, not its figures.
SCOPE = {
    "reports/sections/executive.py": ("backlash_requirement", "verdicts", "build", "_influences"),
    "reports/builder.py": ("insufficient", "n_used"),
}
SETS = {
    "physics": [m for m in TESTS if m.startswith("twin/physics/")],
    "sensors": [m for m in TESTS if m.startswith("sensors/")],
    "analysis": ["campaigns/statistics/detection.py", "campaigns/statistics/sensitivity.py"],
    "reports": ["reports/sections/executive.py", "reports/builder.py", "reports/inputs.py"],
}

#: The issue's "done when" table replayed as deliberate mutations: name -> (module, text, replacement, tests).
#: Each must make its tests fail (``--replay``); the unmutated tests must pass first.
REPLAYS = {
    "report verdict always 'meets'": (
        "reports/sections/executive.py",  # page 1's decision line (the verdict callouts read it the same way)
        'verdict = str(a["requirement_verdict"].sel(feature=feature).item())\n    source_words',
        'verdict = "met"\n    source_words',
        ["tests/reports/test_report_verdicts.py", "tests/reports/test_executive_summary.py"]),
    "analysis verdict always 'met'": (
        "campaigns/statistics/detection.py", "    if upper <= requirement:\n", "    if True:\n",
        ["tests/campaigns/test_campaign_verdict.py", "-k", "not cli_prints"]),
    "curvature option ignored": (
        "twin/engine/model.py", "contact_constants(c, p, curvature)", 'contact_constants(c, p, "thesis")',
        ["tests/engine/test_simulate_api.py", "-k", "iso_curvature"]),
    "torque-meter quantisation removed": (
        "twin/engine/instrumentation.py",
        "memory[M.SCREW_ANGLE, lane] = encoder_reading(states[TORQUE_METER_ENCODER], parameters[TORQUE_METER_ENCODER],"
        "\n                                                      lane)",
        "memory[M.SCREW_ANGLE, lane] = screw_angle_measurand(x, c, lane)",
        ["tests/engine/test_instruments_in_loop.py", "-k", "torque_meter_encoder_is_floor"]),
    "errors() returning 0": (
        "app/studies/work_precision.py",
        '    if ds.attrs["status"] != "ok":\n        return {name: np.nan for name in METRICS}',
        "    return {name: 0.0 for name in METRICS}",
        ["tests/studies/test_speed_accuracy.py", "-k", "error_metrics"]),
}

_ARITHMETIC = [("Add", "Sub"), ("Sub", "Add"), ("Mul", "Div"), ("Div", "Mul"), ("Pow", "Mul")]
_COMPARISON = [("Lt", "LtE"), ("LtE", "Lt"), ("Gt", "GtE"), ("GtE", "Gt"), ("Eq", "NotEq"), ("NotEq", "Eq"),
               ("Lt", "Gt"), ("Gt", "Lt")]
OPERATORS = ([f"core/ReplaceBinaryOperator_{a}_{b}" for a, b in _ARITHMETIC]
             + [f"core/ReplaceComparisonOperator_{a}_{b}" for a, b in _COMPARISON]
             + ["core/ReplaceUnaryOperator_USub_UAdd", "core/AddNot", "core/NumberReplacer",
                "core/ReplaceAndWithOr", "core/ReplaceOrWithAnd", "core/ReplaceTrueWithFalse",
                "core/ReplaceFalseWithTrue", "core/ReplaceBreakWithContinue", "core/ZeroIterationForLoop"])


def enumerate_mutants(module: str, source: str) -> list[tuple[str, str, int, int]]:
    """Every (module, operator, occurrence, line) cosmic-ray's operators offer in ``source``."""
    from cosmic_ray.ast import ast_nodes, get_ast
    from cosmic_ray.plugins import get_operator

    tree = get_ast(source)
    lines = source.splitlines()
    scoped = _scoped_lines(source, SCOPE[module]) if module in SCOPE else None
    mutants = []
    for name in OPERATORS:
        operator = get_operator(name)()
        positions = [start for node in ast_nodes(tree) for start, _ in operator.mutation_positions(node)]
        mutants += [(module, name, occurrence, start[0]) for occurrence, start in enumerate(positions)
                    if not lines[start[0] - 1].lstrip().startswith("@")  # decorator arguments, e.g. cache=True
                    and (scoped is None or start[0] in scoped)]
    return mutants


def _scoped_lines(source: str, functions: tuple[str, ...]) -> set[int]:
    """Line numbers of the bodies (and signatures) of the named functions or methods of ``source``."""
    import ast

    nodes = [n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)
             and n.name in functions]
    missing = set(functions) - {n.name for n in nodes}
    if missing:
        raise SystemExit(f"SCOPE names functions that do not exist (moved or renamed?): {', '.join(sorted(missing))}")
    return {line for n in nodes for line in range(n.lineno, n.end_lineno + 1)}


def wilson(killed: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson score interval of a proportion."""
    if n == 0:
        return math.nan, math.nan
    p = killed / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


class _Timeout(Exception):
    pass


_alarm_rang = False


def _alarm(signum, frame):
    global _alarm_rang
    _alarm_rang = True
    raise _Timeout()


def run_tests(copy: Path, tests: list[str], timeout: float) -> str:
    """Run ``tests`` in-process on the copy's current sources.

    Returns ``"passed"``, ``"failed"`` (a test failed or errored, or collection did), ``"timeout"`` (still running
    after ``timeout`` seconds; the alarm may also surface later as an error of pytest itself, e.g. when it rang
    inside a finaliser), or ``"crashed"`` (pytest itself raised).
    """
    global _alarm_rang
    import pytest

    for name in list(sys.modules):
        top = name.split(".")[0]
        if top in PROJECT_PACKAGES or name.startswith(("test_", "conftest", "bench_helpers", "tests")):
            del sys.modules[name]
    _alarm_rang = False
    signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            # plain Python (NUMBA_DISABLE_JIT) evaluates the discarded side of the branch-free selects too, and numpy
            # warns about its inf/NaN where the compiled code does not: those warnings are not test failures here
            code = pytest.main(["-x", "-q", "-p", "no:cacheprovider", "-W", "ignore::RuntimeWarning",
                                "--rootdir", str(copy),
                                *[str(copy / t) if t.startswith("tests/") else t for t in tests]])
    except _Timeout:
        return "timeout"
    except Exception:
        return "timeout" if _alarm_rang else "crashed"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    if _alarm_rang:
        return "timeout"
    return "passed" if code == 0 else "failed"


def score_set(name: str, modules: list[str], copy: Path, sample: int | None, seed: int, timeout: float,
              progress, only: set | None = None, offset: int = 0) -> dict:
    """Mutate every (or a sample of the) mutation point(s) of ``modules``; return the tally and survivors.
    ``only``: test just these (module, operator, occurrence) triples (``--recheck``); ``offset``: start at this
    position of the random order (to continue a run that was stopped)."""
    from cosmic_ray.mutating import mutate_code
    from cosmic_ray.plugins import get_operator

    originals = {m: (copy / m).read_text() for m in modules}
    budget, measured = {}, {}
    for module in modules:
        key = tuple(TESTS[module])
        if key not in measured:  # once per distinct test list
            began = time.perf_counter()
            outcome = run_tests(copy, TESTS[module], 10 * timeout)
            if outcome != "passed":
                raise SystemExit(f"{module}: its tests are {outcome} without any mutation; fix them first")
            measured[key] = time.perf_counter() - began
        # a mutant that makes the tests run far longer than unmutated counts as killed (an infinite loop); the
        # margin is relative, so a busy machine slows both alike and no survivor is taken for a timeout
        budget[module] = max(timeout, 10 * measured[key])
    package = modules[0].split("/")[0]
    imported = Path(sys.modules[package].__file__).resolve()
    if copy.resolve() not in imported.parents:
        raise SystemExit(f"the tests imported {imported}, not the mutated copy in {copy}")
    mutants = [mutant for m in modules for mutant in enumerate_mutants(m, originals[m])]
    total = len(mutants)
    # tested in a seeded random order: a run stopped early has still tested a random sample (the running tally of
    # the --verbose lines is its score)
    mutants = random.Random(seed).sample(mutants, total if sample is None else min(sample, total))[offset:]
    if only is not None:
        mutants = [m for m in mutants if (m[0], m[1].removeprefix("core/"), m[2]) in only]
    killed, survivors, timeouts = 0, [], 0
    start = time.perf_counter()
    for i, (module, operator, occurrence, line) in enumerate(mutants, 1):
        mutated = mutate_code(originals[module], get_operator(operator)(), occurrence)
        if mutated is None:
            killed += 1  # nothing to mutate: counted as killed so it cannot inflate the survivors
            continue
        (copy / module).write_text(mutated)
        try:
            outcome = run_tests(copy, TESTS[module], budget[module])
        finally:
            (copy / module).write_text(originals[module])
        survived = outcome == "passed"
        if survived:
            survivors.append((module, line, operator.removeprefix("core/"), occurrence,
                              _changed_line(originals[module], mutated)))
        else:
            killed += 1
            timeouts += outcome == "timeout"
        progress(f"[{name}] {i}/{len(mutants)} {'SURVIVED' if survived else 'killed  '} {module}:{line} "
                 f"{operator.removeprefix('core/')} #{occurrence} ({outcome}; {killed}/{i} killed so far)")
    return {"set": name, "modules": modules, "mutants_total": total, "tested": len(mutants), "killed": killed,
            "timeouts": timeouts, "survivors": survivors, "seconds": time.perf_counter() - start}


def replay(copy: Path, timeout: float, baseline: bool) -> bool:
    """Apply each of :data:`REPLAYS` in turn; True when the tests catch every one (and pass without it)."""
    caught_all = True
    for name, (module, text, replacement, tests) in REPLAYS.items():
        original = (copy / module).read_text()
        if original.count(text) != 1:
            raise SystemExit(f"replay {name!r}: {module} does not contain the text to mutate exactly once (moved?)")
        before = run_tests(copy, tests, 10 * timeout) if baseline else "not run"
        (copy / module).write_text(original.replace(text, replacement))
        try:
            after = run_tests(copy, tests, 10 * timeout)
        finally:
            (copy / module).write_text(original)
        caught = after in ("failed", "timeout") and before in ("passed", "not run")
        caught_all &= caught
        print(f"replay {name}: {module}: unmutated {before}, mutated {after} -> {'CAUGHT' if caught else 'MISSED'} "
              f"by {' '.join(tests)}", flush=True)
    return caught_all


def _changed_line(original: str, mutated: str) -> str:
    for a, b in zip(original.splitlines(), mutated.splitlines(), strict=False):
        if a != b:
            return f"{a.strip()}  ->  {b.strip()}"
    return "(no textual change)"


def make_copy() -> Path:
    """A private copy of the sources and tests (mutants are written only there)."""
    copy = Path(tempfile.mkdtemp(prefix="benchtwin-mutants-"))
    for item in COPIED:
        source = ROOT / item
        if source.is_dir():
            shutil.copytree(source, copy / item, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
        else:
            shutil.copy2(source, copy / item)
    return copy


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sets", nargs="+", choices=sorted(SETS), default=list(SETS))
    parser.add_argument("--sample", type=int, help="test a fixed-seed random sample of this many mutants per set")
    parser.add_argument("--all", action="store_true", help="test every mutant (default when --sample is absent)")
    parser.add_argument("--quick", action="store_true", help="CI mode: the physics set, a 40-mutant sample")
    parser.add_argument("--seed", type=int, default=20)
    parser.add_argument("--offset", type=int, default=0, help="start at this position of the seeded random order "
                        "(continue a stopped run)")
    parser.add_argument("--timeout", type=float, default=60.0,
                        help="seconds per mutant before it counts as killed, at least (10x the unmutated tests' time)")
    parser.add_argument("--min-score", type=float, default=None, help="exit 1 when a set scores below this (0-1)")
    parser.add_argument("--replay", action="store_true", help="apply the issue's deliberate mutations (REPLAYS) "
                        "instead, each once, and check that their tests catch them")
    parser.add_argument("--no-baseline", action="store_true", help="with --replay: skip the unmutated run of the tests")
    parser.add_argument("--verbose", action="store_true", help="print every mutant's outcome")
    parser.add_argument("--recheck", type=Path, help="re-test only the survivors listed in an earlier output of "
                                                      "this script (after adding tests that should kill them)")
    args = parser.parse_args(argv)
    if args.quick:
        args.sets, args.sample = ["physics"], args.sample or 40
    if os.environ.get("NUMBA_DISABLE_JIT") != "1":
        # the environment must be set before numba is imported: re-run this script with it
        env = dict(os.environ, NUMBA_DISABLE_JIT="1")
        # exec, not a child process: a signal sent to this process reaches the run itself
        os.execve(sys.executable, [sys.executable, __file__, *(argv if argv is not None else sys.argv[1:])], env)

    only = None
    if args.recheck:
        listed = re.finditer(r"survived (\S+?):(\d+) (\S+) #(\d+)", args.recheck.read_text())
        only = {(m[1], m[3], int(m[4])) for m in listed}
        args.all = args.all or args.sample is None
    copy = make_copy()
    def stop(signum, frame):
        # pytest would catch a SystemExit or KeyboardInterrupt raised inside a test run and count the mutant as
        # killed: remove the copy and leave at once instead
        shutil.rmtree(copy, ignore_errors=True)
        os._exit(128 + signum)

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    os.chdir(copy)
    sys.path.insert(0, str(copy))
    sys.path.insert(0, str(copy / "tests"))
    progress = (lambda line: print(line, flush=True)) if args.verbose else (lambda line: None)
    failed = False
    try:
        if args.replay:
            return 0 if replay(copy, args.timeout, not args.no_baseline) else 1
        for name in args.sets:
            result = score_set(name, SETS[name], copy, None if args.all else args.sample, args.seed, args.timeout,
                               progress, only, args.offset)
            tested, killed = result["tested"], result["killed"]
            low, high = wilson(killed, tested)
            sampled = f"a sample of {tested} of {result['mutants_total']}" if tested < result["mutants_total"] \
                else f"all {tested}"
            if tested == 0:
                continue
            print(f"{name}: {killed}/{tested} mutants killed = {killed / tested:.1%} "
                  f"(95 % CI {low:.1%}-{high:.1%}; {sampled} mutants of {len(result['modules'])} modules; "
                  f"{result['seconds']:.0f} s; {result['timeouts']} killed by a timeout)")
            for module, line, operator, occurrence, change in result["survivors"]:
                print(f"    survived {module}:{line} {operator} #{occurrence}: {change}")
            if args.min_score is not None and killed / tested < args.min_score:
                failed = True
    finally:
        os.chdir(ROOT)
        shutil.rmtree(copy, ignore_errors=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
