"""The same spec and seed give the same numbers whatever executes them: BLAS kernel, BLAS thread count, numpy's
SIMD dispatch and numba's code-generation target (issue 28; docs/campaigns.md, "The same numbers everywhere").

Each case runs, in a fresh process with one part of the environment changed, the golden campaign of
``test_golden_results.py`` (compared bit for bit with the stored golden file), one free-nut run, ``ds2`` with
noise seed 3, whose Eq. 9.12 feature amplifies any last-bit difference in the model constants (its f_b moved by
0.058 um between two OpenBLAS kernels before the run path was cleared of BLAS/LAPACK calls), and a lane group of
three runs of three data sets (``twin.simulate_batch``, 3 lanes against the host's group of 8: another lane count
and, under the generic target, another vector width for the lane kernels; the same compiled functions, so no extra
compilation).

Which environments: OpenBLAS picks its kernel from the CPU unless ``OPENBLAS_CORETYPE`` names one, and a kernel the
CPU cannot execute kills the process (SkylakeX on a CPU without AVX-512), so the cases are chosen from the
machine's own instruction set: the oldest x86-64 kernel (Prescott) with one BLAS thread everywhere; Haswell where
the CPU has AVX-512 (its default is then SkylakeX), else Sandybridge (the default being Haswell or Zen); numpy
restricted to its baseline kernels (``NPY_DISABLE_CPU_FEATURES``) with two BLAS threads; and, for the single run,
numba compiling for a generic x86-64 target (SSE2: another vector width than the host's, no FMA).
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest
import xarray as xr

import twin

ROOT = Path(__file__).resolve().parents[2]
GOLDEN_SCRIPT = ROOT / "scripts" / "golden_results.py"
_spec = importlib.util.spec_from_file_location("golden_results", GOLDEN_SCRIPT)
golden_results = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(golden_results)

#: Environment variables that choose numeric kernels; cleared in every child, then set per case.
KERNEL_VARIABLES = ("OPENBLAS_CORETYPE", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "NPY_DISABLE_CPU_FEATURES",
                    "NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES")
#: numpy's dispatch targets above its x86-64 baseline (numpy 2.x names; unknown names are ignored by numpy).
NUMPY_DISPATCH_TARGETS = "X86_V3 X86_V4 AVX512_ICL AVX512_SPR AVX2 FMA3 AVX512F AVX512_SKX"

CHILD = """
import importlib.util, pathlib, sys, tempfile
spec = importlib.util.spec_from_file_location("golden_results", sys.argv[1])
golden = importlib.util.module_from_spec(spec)
spec.loader.exec_module(golden)
import twin
if sys.argv[2] != "-":
    with tempfile.TemporaryDirectory() as tmp:
        golden.run_golden_campaign(pathlib.Path(tmp) / "out").to_netcdf(sys.argv[2])
print(" ".join(float(s.features[f]).hex() for s in twin.simulate_batch(
    [("ds2", None, 4), ("ds1", None, 5), ("ds5", None, 6)], solver=twin.Solver(lanes=3), duration=2.0)
    for f in ("backlash_feature", "backlash_feature_true")))
print(float(twin.simulate("ds2", save="features", rng=3).features["backlash_feature"]).hex())
"""
#: The lane group of the child, as the host computes it (in one group of the default 16 lanes).
GROUP = [("ds2", None, 4), ("ds1", None, 5), ("ds5", None, 6)]


def _cpu_flags() -> set[str]:
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return set()
    for line in text.splitlines():
        if line.startswith("flags"):
            return set(line.split(":", 1)[1].split())
    return set()


def _cases() -> list[tuple[str, dict[str, str], bool]]:
    """``(label, environment, run the golden campaign too)`` for this machine (module docstring)."""
    avx512 = "avx512f" in _cpu_flags()
    second = "Haswell" if avx512 else "Sandybridge"
    return [
        ("OpenBLAS Prescott kernel, 1 BLAS thread", {"OPENBLAS_CORETYPE": "Prescott", "OPENBLAS_NUM_THREADS": "1"},
         True),
        (f"OpenBLAS {second} kernel, 2 BLAS threads", {"OPENBLAS_CORETYPE": second, "OPENBLAS_NUM_THREADS": "2"},
         True),
        ("numpy baseline kernels only", {"NPY_DISABLE_CPU_FEATURES": NUMPY_DISPATCH_TARGETS}, True),
        ("numba generic x86-64 target", {"NUMBA_CPU_NAME": "generic"}, False),
    ]


def _child(env: dict[str, str], campaign_out: Path | None) -> tuple[str, str]:
    """The child's single-run f_b and its lane group's features (hex)."""
    environment = {k: v for k, v in os.environ.items() if k not in KERNEL_VARIABLES}
    environment.update(env)
    done = subprocess.run([sys.executable, "-c", CHILD, str(GOLDEN_SCRIPT), str(campaign_out or "-")],
                          env=environment, cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, f"child failed ({done.returncode}):\n{done.stderr[-3000:]}"
    group, single = done.stdout.strip().splitlines()[-2:]
    return single, group


@pytest.fixture(scope="module")
def reference_feature() -> str:
    """The free-nut run's f_b in this process's own environment."""
    return float(twin.simulate("ds2", save="features", rng=3).features["backlash_feature"]).hex()


@pytest.fixture(scope="module")
def reference_group() -> str:
    """The lane group's features in this process's own environment, in a group of the default lane count."""
    return " ".join(float(s.features[f]).hex() for s in twin.simulate_batch(GROUP, duration=2.0)
                    for f in ("backlash_feature", "backlash_feature_true"))


@pytest.mark.slow
@pytest.mark.parametrize("label, env, campaign", _cases(), ids=[case[0] for case in _cases()])
def test_bit_identical_whatever_executes_it(label, env, campaign, reference_feature, reference_group, tmp_path):
    out = tmp_path / "golden.nc" if campaign else None
    feature, group = _child(env, out)
    assert feature == reference_feature, f"{label}: ds2 f_b {float.fromhex(feature)!r} != {reference_feature}"
    assert group == reference_group, f"{label}: the lane group's features differ: {group} != {reference_group}"
    if campaign:
        with xr.open_dataset(out) as new, xr.open_dataset(golden_results.GOLDEN) as stored:
            differences = golden_results.differences(new.load(), stored.load())
        assert not differences, f"{label}: results differ from the golden file:\n" + "\n".join(differences)
