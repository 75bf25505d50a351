"""The CUDA engine (:mod:`twin.engine.cuda`) against the CPU lane engine, bit for bit, under numba's CUDA simulator.

The parent process runs short groups on the compiled CPU engine and captures what :func:`twin.engine.group.solve_group`
got and gave; a child process with ``NUMBA_ENABLE_CUDASIM=1 NUMBA_DISABLE_JIT=1`` runs the same groups through
:func:`twin.engine.cuda.solve_group_cuda` (one simulated thread per run, on its column views) and the state, the
loop memory (the feature accumulators), the output and the status are compared bit for bit. The simulator runs the
engine's plain Python functions, the source NVVM compiles: this checks the kernel's plumbing (thread to lane views,
per-thread scratch, copy in and out) and the source's semantics, not NVVM's code (tests/engine/test_cuda_ptx.py) and
not a GPU's speed. The simulator costs ~5-20 ms per thread and step on the loaded 2-core machine, so the runs are
80-160 steps: too short for the features (NaN that early), long enough for every stage, the guard's local-error
checks and, for the W-method, several matrix refreshes.
"""

from __future__ import annotations

import contextlib
import inspect
import os
import pickle
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import twin
import twin.simulation
from twin.engine import cuda as engine_cuda
from twin.engine import group
from twin.engine.group import loop_arguments, solve_group
from twin.engine.loop import run_loop

ROOT = Path(__file__).resolve().parents[2]
#: The compared results of a group (twin.engine.group.Solved's fields).
RESULTS = ("state", "memory", "output", "status", "bound", "steps_done", "rows_written")


def _groups() -> dict[str, dict]:
    """Short groups on the CPU engine (RK4 with two runs, the W-method with its signals recorded, IMEX with two runs
    at the dynamic screw-axial level): each group's ``solve_group`` arguments and results."""
    captured = []
    params = twin.load_parameters()
    runs = [("ds1", params.with_values({"motor.torque_constant": params.value("motor.torque_constant") * f}), seed)
            for f, seed in ((1.0, 101), (1.02, 102))]
    with _captured(captured):
        twin.simulate_batch(runs, duration=0.01, solver=twin.Solver(lanes=2))                  # RK4 at 125 us: 80 steps
        twin.simulate("ds3", params, duration=0.005, rng=7, solver=twin.Solver("rosenbrock_w2"))  # 62.5 us: 80 steps
        twin.simulate_batch(runs, duration=0.01, fidelity={"screw_axial": "dynamic"},
                            solver=twin.Solver("imex_euler", lanes=2))                         # 62.5 us: 160 steps
    return dict(zip(("rk4", "rosenbrock_w2", "imex_euler"), captured, strict=True))


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    """The CPU's and the simulated GPU's results of every group."""
    groups = _groups()
    folder = tmp_path_factory.mktemp("cuda_simulator")
    inputs, outputs = folder / "groups.pickle", folder / "results.npz"
    inputs.write_bytes(pickle.dumps({k: {n: g[n] for n in ("models", "instruments", "options")}
                                     for k, g in groups.items()}))
    env = {**os.environ, "NUMBA_ENABLE_CUDASIM": "1", "NUMBA_DISABLE_JIT": "1", "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, __file__, str(inputs), str(outputs)], env=env, cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    simulated = np.load(outputs)
    return {k: (g["results"], {n: simulated[f"{k}.{n}"] for n in RESULTS}) for k, g in groups.items()}


@pytest.mark.parametrize("method", ["rk4", "rosenbrock_w2", "imex_euler"])
def test_a_thread_per_run_gives_the_cpu_lane_engines_bits(compared, method):
    cpu, gpu = compared[method]
    assert cpu["steps_done"].min() > 0 and np.all(cpu["status"] == 0)  # the runs ran to the end on the CPU
    for name in RESULTS:
        assert cpu[name].dtype == gpu[name].dtype and cpu[name].shape == gpu[name].shape, name
        assert np.array_equal(cpu[name].view(np.uint8), gpu[name].view(np.uint8)), f"{name} differs"
    if method == "rosenbrock_w2":
        assert cpu["rows_written"][0] > 1  # the recorded signals were compared too


def test_the_kernel_passes_the_loop_its_arguments_in_its_order():
    """``loop_arguments`` names every argument of ``run_loop``, in order (the kernel passes them by position)."""
    expected = list(inspect.signature(getattr(run_loop, "py_func", run_loop)).parameters)
    assert list(inspect.signature(engine_cuda._kernel.py_func).parameters) == expected
    models, instruments, options = _one_model()
    assert list(loop_arguments(models, instruments, **options)) == expected


@pytest.mark.skipif(not engine_cuda.unavailable(), reason="a CUDA GPU is available here")
def test_without_a_gpu_the_engine_says_why_before_any_work(tmp_path, capsys):
    with pytest.raises(twin.OptionError, match=r"engine: 'cuda' cannot run here: .*GPU"):
        twin.Solver(engine="cuda")
    from app.cli import main

    out = tmp_path / "run.nc"
    assert main(["simulate", "ds1", "--engine", "cuda", "--out", str(out)]) == 2
    assert "engine: 'cuda' cannot run here: no usable NVIDIA GPU" in capsys.readouterr().err and not out.exists()
    assert main(["campaign", "run", str(ROOT / "campaigns/specs/thesis_backlash.toml"), "--engine", "cuda",
                 "--out", str(tmp_path / "campaign")]) == 2
    assert "engine: 'cuda' cannot run here" in capsys.readouterr().err and not (tmp_path / "campaign").exists()
    models, instruments, options = _one_model()
    with pytest.raises(RuntimeError, match="engine 'cuda': no usable NVIDIA GPU"):
        engine_cuda.solve_group_cuda(models, instruments, **options)


def _one_model():
    """A one-run group's ``solve_group`` arguments."""
    captured = []
    with _captured(captured):
        twin.simulate("ds1", duration=0.001, save="features")
    return captured[0]["models"], captured[0]["instruments"], captured[0]["options"]


@contextlib.contextmanager
def _captured(into: list):
    """Record every CPU group solved inside: its ``solve_group`` arguments and results."""
    def spy(models, instruments, **options):
        result = solve_group(models, instruments, **options)
        into.append({"models": list(models), "instruments": list(instruments), "options": options,
                     "results": {name: getattr(result, name).copy() for name in RESULTS}})
        return result

    targets = [module for module in (twin.simulation, group) if hasattr(module, "solve_group")]
    for module in targets:
        module.solve_group = spy
    try:
        yield
    finally:
        for module in targets:
            module.solve_group = solve_group


def _simulate_on_threads(inputs: str, outputs: str) -> None:
    """The child process: every group through the CUDA engine under the simulator."""
    assert engine_cuda.unavailable() == "", engine_cuda.unavailable()
    # as compiled (error_model="numpy"), a division by zero is an IEEE inf or nan, not news (np.seterr is per thread)
    warnings.simplefilter("ignore", RuntimeWarning)
    groups = pickle.loads(Path(inputs).read_bytes())
    arrays = {}
    for key, given in groups.items():
        result = engine_cuda.solve_group_cuda(given["models"], given["instruments"], **given["options"])
        arrays.update({f"{key}.{name}": getattr(result, name) for name in RESULTS})
    np.savez(outputs, **arrays)


if __name__ == "__main__":
    _simulate_on_threads(*sys.argv[1:3])
