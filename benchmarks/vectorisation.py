"""Do the lane loops vectorise? The assembly of small lane kernels over each elementary function, and their speed.

Lock-step lanes (issue 32) pay only if a loop over the lanes of a group becomes packed vector code, and they keep
their promise (the same bits for one sample alone as in any group) only if that code contains no fused
multiply-add (numba never emits LLVM's ``contract`` flag without fastmath, so an FMA here would mean that
changed). This script compiles one ``KERNEL`` lane loop per function of :mod:`numerics.elementary` (and over one
or two physics laws of ``twin.physics`` if they are ``SCALAR``, i.e. ported for lanes, and import cleanly) and reads
its assembly (``dispatcher.inspect_asm``):

* packed double arithmetic (``addpd``, ``mulpd``, ..., ``blendvpd``, ``cmppd``) per register width (zmm, ymm, xmm)
  against scalar ``...sd`` instructions (the remainder loop for ``lanes % VF`` lanes and the scalar prologue);
* FMA instructions (``vfmadd...``, ``vfnmsub...``): there must be none;
* the smallest lane count that enters the vector loop (LLVM's ``min.iters.check`` in the IR: VF x interleave):
  a group of 8 lanes must reach it.

A kernel whose loop did not vectorise (no packed arithmetic at the target's widest vector width), whose vector
loop needs more than 8 lanes, or that contains an FMA, prints FAIL and makes the script exit with status 1 (CI
runs it). The kernels are compiled without numba's disk cache: numba cannot show the assembly of cached code.

Then, indicative only (a shared 2-core Zen 3 without AVX-512; CPU time, ``time.process_time``), ns per evaluation
of each function in three forms, all in this invocation: glibc through numba (``math.*``, scalar calls: a loop
with a libm call does not vectorise), ours scalar (the same lane kernels compiled in a child process with LLVM's
loop and SLP vectorisers off and its own numba cache), ours in the lane loop (groups of 16 lanes, one kernel call
per group). Min and median over interleaved rounds of about 10 ms each (3 ms with ``--quick``).

Usage: python benchmarks/vectorisation.py [--rounds 7] [--quick] [--assembly-only]
       NUMBA_CPU_NAME=znver4 python benchmarks/vectorisation.py --assembly-only   (another target's code, not run)
"""

from __future__ import annotations

import argparse
import inspect
import json
import math
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numba
import numpy as np
from machine import header
from numba.core import config

from numerics import elementary
from numerics.jit import KERNEL

#: Lane-kernel options without the disk cache (numba returns no assembly for cached code).
INSPECTABLE = {**KERNEL, "cache": False}
#: Lanes per group in the timing; the vector loop must be entered by groups of MAX_MIN_LANES lanes.
LANES = 16
MAX_MIN_LANES = 8
GROUPS = 256
#: numba type of one contiguous row of a group (the kernels' arguments)
ROW = numba.float64[::1]

#: name -> (our function, glibc's through numba or None for x ** 0.26, argument range the model uses)
FUNCTIONS = {
    "exp": (elementary.exp, math.exp, (-50.0, 0.0)),          # Stribeck: exp(-a |v|)
    "expm1": (elementary.expm1, math.expm1, (-40.0, 0.0)),    # first-order lag: expm1(-dt / tau)
    "log": (elementary.log, math.log, (1e-3, 1e5)),
    "tanh": (elementary.tanh, math.tanh, (-30.0, 30.0)),      # tanh(v / v_threshold)
    "sin": (elementary.sin, math.sin, (-1e4, 1e4)),           # encoder angles
    "cos": (elementary.cos, math.cos, (-1e4, 1e4)),
    "pow026": (elementary.pow026, None, (1e-3, 1e5)),         # rolling friction: normal load^0.26 [N]
}

#: (module, law): physics laws compiled into a lane kernel too when they are SCALAR (forceinline) float functions.
PHYSICS_LAWS = (("twin.physics.friction", "stribeck_friction"),
                ("twin.physics.ball_groove_friction", "nut_friction_force"))

PACKED = re.compile(r"\bv?(?:add|sub|mul|div|sqrt|max|min|blendv|cmp\w*|and|andn|or|xor)pd\b[^\n]*")
SCALAR_SD = re.compile(r"\bv?(?:add|sub|mul|div|sqrt|max|min)sd\b")
FMA = re.compile(r"\bvf(?:n?)m(?:add|sub)\w*")
#: LLVM's guard of the vector loop: ``ult N`` (fewer than N lanes: scalar loop only); ``eq N`` / ``ule N`` where it
#: knows the trip count is at least N (VF 2 on SSE2: ``eq 1``), i.e. N + 1 lanes needed.
MIN_ITERS = re.compile(r"min\.iters\.check\S* = icmp (ult|ule|eq) i64 %\S+, (\d+)")


# ----------------------------------------------------------------------------------------------------------
# kernels
# ----------------------------------------------------------------------------------------------------------
def lane_kernel(function):
    """A lane loop over one group: ``y[lane] = function(x[lane])``, KERNEL options, not cached."""
    def kernel(x, y):
        for lane in range(x.shape[0]):
            y[lane] = function(x[lane])
    return numba.njit(**INSPECTABLE)(kernel)


def libm_kernel(function):
    """The same loop over glibc's function (numba lowers ``math.*`` to libm calls; ``x ** 0.26`` to ``pow``)."""
    if function is None:
        def kernel(x, y):
            for lane in range(x.shape[0]):
                y[lane] = x[lane] ** 0.26
    else:
        def kernel(x, y):
            for lane in range(x.shape[0]):
                y[lane] = function(x[lane])
    return numba.njit(error_model="numpy", boundscheck=False)(kernel)


def physics_kernel(law, arity):
    """A lane loop over a law of ``arity`` float arguments, rows of ``a[argument, lane]``."""
    arguments = ", ".join(f"a[{i}, lane]" for i in range(arity))
    source = f"def kernel(a, y):\n    for lane in range(y.shape[0]):\n        y[lane] = law({arguments})\n"
    namespace = {"law": law}
    exec(source, namespace)  # noqa: S102 - the source is built here from an integer
    return numba.njit(**INSPECTABLE)(namespace["kernel"])


@numba.njit
def drive(kernel, x, y, repeats):
    """Every group of ``x[group, lane]`` through ``kernel``, ``repeats`` times: one kernel call per group, as the
    engine calls its lane kernels."""
    for _ in range(repeats):
        for group in range(x.shape[0]):
            kernel(x[group], y[group])


# ----------------------------------------------------------------------------------------------------------
# assembly
# ----------------------------------------------------------------------------------------------------------
def target_vector_width() -> str:
    """The widest vector register numba's target may use: 'zmm', 'ymm' or 'xmm' (from its CPU features)."""
    features = config.CPU_FEATURES
    if features is None:
        from llvmlite import binding  # lazy: only to read the host's features

        enabled = {name for name, on in binding.get_host_cpu_features().items() if on}
    else:
        enabled = {f[1:] for f in features.split(",") if f.startswith("+")}
    if "avx512f" in enabled:
        return "zmm"   # LLVM may still prefer ymm (prefer-256-bit tuning): both count as vectorised there
    return "ymm" if "avx" in enabled else "xmm"


def inspect_kernel(kernel) -> dict:
    signature = kernel.signatures[0]
    asm = kernel.inspect_asm(signature)
    packed = [m.group(0) for m in PACKED.finditer(asm)]
    zmm = sum("zmm" in line for line in packed)
    ymm = sum("ymm" in line for line in packed)
    trips = sorted({int(n) + (op != "ult") for op, n in MIN_ITERS.findall(kernel.inspect_llvm(signature))})
    return {"zmm": zmm, "ymm": ymm, "xmm": len(packed) - zmm - ymm, "scalar": len(SCALAR_SD.findall(asm)),
            "fma": len(FMA.findall(asm)), "min_lanes": trips[0] if trips else None}


def verdict(counts: dict, width: str) -> tuple[bool, str]:
    wide = counts["zmm"] + counts["ymm"] if width in ("zmm", "ymm") else counts["xmm"]
    problems = []
    if wide == 0:
        problems.append(f"not vectorised (no packed {'ymm/zmm' if width != 'xmm' else 'xmm'} arithmetic)")
    if counts["fma"]:
        problems.append(f"{counts['fma']} FMA instructions (contraction: bits would depend on the CPU)")
    if counts["min_lanes"] is not None and counts["min_lanes"] > MAX_MIN_LANES:
        problems.append(f"vector loop needs {counts['min_lanes']} lanes (> {MAX_MIN_LANES})")
    if problems:
        return False, "FAIL: " + "; ".join(problems)
    trip = "?" if counts["min_lanes"] is None else counts["min_lanes"]
    return True, f"OK: vectorised, no FMA, vector loop from {trip} lanes"


def physics_kernels(width: str) -> list[tuple[str, object]]:
    """Lane kernels over the physics laws that are SCALAR and import cleanly; the others are reported skipped."""
    kernels = []
    for module_name, law_name in PHYSICS_LAWS:
        label = f"{module_name.rsplit('.', 1)[-1]}.{law_name}"
        try:
            module = __import__(module_name, fromlist=[law_name])
            law = getattr(module, law_name)
        except Exception as error:  # noqa: BLE001 - twin.physics is being rewritten; say why and go on
            print(f"# {label}: skipped, it does not import ({type(error).__name__}: {error})")
            continue
        if not getattr(law, "targetoptions", {}).get("forceinline"):
            print(f"# {label}: skipped, not a SCALAR law yet (no forceinline: its calls stay calls and no lane "
                  f"loop over it can vectorise)")
            continue
        arity = len(inspect.signature(law.py_func).parameters)
        try:
            kernel = physics_kernel(law, arity)
            kernel.compile((numba.float64[:, ::1], ROW))
        except Exception as error:  # noqa: BLE001 - e.g. a law returning a tuple: not a one-float law
            print(f"# {label}: skipped, no one-float lane kernel ({type(error).__name__}: "
                  f"{str(error).splitlines()[0]})")
            continue
        kernels.append((label, kernel))
    return kernels


def assembly_section() -> tuple[bool, dict]:
    """Print the table and the verdicts; returns (all OK, the elementary functions' kernels by name)."""
    width = target_vector_width()
    cpu = config.CPU_NAME or "host"
    print(f"\n## Assembly of the lane kernels (numba target {cpu}, widest vector register {width})")
    kernels = []
    for name, (function, _, _) in FUNCTIONS.items():
        kernel = lane_kernel(function)
        kernel.compile((ROW, ROW))         # compiled, not run: --assembly-only works for a foreign target too
        kernels.append((name, kernel))
    kernels += physics_kernels(width)
    print(f"{'kernel':32s} {'packed zmm':>10s} {'ymm':>5s} {'xmm':>5s} {'scalar sd':>10s} {'FMA':>4s} "
          f"{'vector from L':>14s}")
    ok_all = True
    verdicts = []
    for name, kernel in kernels:
        counts = inspect_kernel(kernel)
        trip = "?" if counts["min_lanes"] is None else str(counts["min_lanes"])
        print(f"{name:32s} {counts['zmm']:10d} {counts['ymm']:5d} {counts['xmm']:5d} {counts['scalar']:10d} "
              f"{counts['fma']:4d} {trip:>14s}")
        ok, text = verdict(counts, width)
        ok_all &= ok
        verdicts.append(f"verdict {name}: {text}")
    print("\n".join(verdicts))
    return ok_all, {name: kernel for name, kernel in kernels if name in FUNCTIONS}


# ----------------------------------------------------------------------------------------------------------
# timing
# ----------------------------------------------------------------------------------------------------------
def arguments(lo: float, hi: float, rng) -> np.ndarray:
    shape = (GROUPS, LANES)
    if lo > 0 and hi / lo > 100:
        return np.exp(rng.uniform(math.log(lo), math.log(hi), shape))
    return rng.uniform(lo, hi, shape)


def time_kernels(kernels: dict, rounds: int, round_seconds: float) -> dict[str, list[float]]:
    """ns per evaluation of each ``kernels[key] = (kernel, x)`` over interleaved rounds (CPU time)."""
    repeats, outputs = {}, {}
    for key, (kernel, x) in kernels.items():
        outputs[key] = np.empty_like(x)
        drive(kernel, x, outputs[key], 1)                     # compile
        start = time.process_time()
        drive(kernel, x, outputs[key], 3)
        per_repeat = max((time.process_time() - start) / 3, 1e-7)
        repeats[key] = max(1, int(round_seconds / per_repeat))
    times = {key: [] for key in kernels}
    for _ in range(rounds):
        for key, (kernel, x) in kernels.items():
            start = time.process_time()
            drive(kernel, x, outputs[key], repeats[key])
            times[key].append((time.process_time() - start) / (repeats[key] * x.size) * 1e9)
    return times


def ours_kernels(compiled: dict | None = None) -> dict:
    """name -> (our lane kernel, its arguments); ``compiled``: kernels already compiled, by name."""
    rng = np.random.default_rng(3)
    compiled = compiled or {}
    return {name: (compiled.get(name) or lane_kernel(function), arguments(*span, rng))
            for name, (function, _, span) in FUNCTIONS.items()}


def scalar_child(rounds: int, round_seconds: float) -> None:
    """The child: our lane kernels compiled without vectorisation; prints the times and the packed (ymm/zmm)
    instruction count of its kernels (0: scalar code) as JSON."""
    kernels = ours_kernels()
    times = time_kernels(kernels, rounds, round_seconds)
    packed = 0
    for kernel, _ in kernels.values():
        counts = inspect_kernel(kernel)
        packed += counts["ymm"] + counts["zmm"]
    print(json.dumps({"times": times, "packed": packed}))


def timing_section(rounds: int, round_seconds: float, compiled: dict) -> None:
    print(f"\n## ns per evaluation (indicative: shared machine; min / median of {rounds} rounds, CPU time)")
    with tempfile.TemporaryDirectory(prefix="vectorisation-scalar-") as cache:
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        env.update(NUMBA_LOOP_VECTORIZE="0", NUMBA_SLP_VECTORIZE="0", NUMBA_CACHE_DIR=cache)
        child = subprocess.run([sys.executable, __file__, "--scalar-child", "--rounds", str(rounds),
                                "--round-seconds", str(round_seconds)], env=env, capture_output=True, text=True)
    scalar = json.loads(child.stdout.splitlines()[-1]) if child.returncode == 0 else {"times": {}, "packed": None}
    if child.returncode != 0:
        print(f"# the scalar child failed; its column is empty:\n{child.stderr[-2000:]}")
    else:
        print(f"# ours scalar: the same kernels in a child process with NUMBA_LOOP_VECTORIZE=0 NUMBA_SLP_VECTORIZE=0 "
              f"and its own cache ({scalar['packed']} packed ymm/zmm instructions in its kernels)")
    kernels = {}
    for name, (kernel, x) in ours_kernels(compiled).items():
        kernels[(name, "libm")] = (libm_kernel(FUNCTIONS[name][1]), x)
        kernels[(name, "lanes")] = (kernel, x)
    times = time_kernels(kernels, rounds, round_seconds)
    columns = ("glibc scalar (math.*)", "ours scalar", f"ours, lane loop L={LANES}", "glibc / ours lanes")
    print(f"{'function':12s}" + "".join(f"{c:>24s}" for c in columns))
    for name, (_, libm, span) in FUNCTIONS.items():
        cells = []
        for values in (times[(name, "libm")], scalar["times"].get(name), times[(name, "lanes")]):
            cells.append("-" if not values else f"{min(values):.2f} / {statistics.median(values):.2f}")
        ratio = statistics.median(times[(name, "libm")]) / statistics.median(times[(name, "lanes")])
        cells.append(f"{ratio:.1f}x")
        label = name if libm is not None else f"{name} (pow)"
        print(f"{label:12s}" + "".join(f"{c:>24s}" for c in cells) + f"   x in [{span[0]:g}, {span[1]:g}]")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--round-seconds", type=float, default=0.01, help=argparse.SUPPRESS)
    parser.add_argument("--quick", action="store_true", help="3 short rounds of timing (the assembly is the same)")
    parser.add_argument("--assembly-only", action="store_true",
                        help="no timing: e.g. NUMBA_CPU_NAME=znver4 to read another target's code on this machine")
    parser.add_argument("--scalar-child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.scalar_child:
        scalar_child(args.rounds, args.round_seconds)
        return
    if args.quick:
        args.rounds, args.round_seconds = 3, 0.003
    header("vectorisation of the lane kernels: packed vs scalar instructions, FMA, minimum lanes; ns per "
           "evaluation", args.quick)
    print(f"# {platform.machine()}; numba target {config.CPU_NAME or 'host'} "
          f"{'(features ' + config.CPU_FEATURES + ')' if config.CPU_FEATURES else ''}")
    ok, compiled = assembly_section()
    if not args.assembly_only:
        timing_section(args.rounds, args.round_seconds, compiled)
    if not ok:
        print("\nFAIL: a lane kernel did not vectorise, needs too many lanes, or contains an FMA (verdicts above)")
        sys.exit(1)
    print("\nall lane kernels vectorised, without FMA")


if __name__ == "__main__":
    main()
