"""The CUDA engine's code as NVVM makes it, checked without a GPU: a real lane stage of the CPU engine compiled to PTX
with the target changes of :mod:`numerics.cuda_target` (no driver needed: :func:`numerics.cuda_target.offline`).

What makes the GPU's bits the CPU's is in the PTX: no fused multiply-add (``fma.rn.f64`` rounds once where the CPU
rounds twice) and every multiply and add with its rounding modifier (``mul.rn.f64``: ptxas may fuse a plain
``mul.f64``/``add.f64``, the PTX ISA's words, so none may be left). The simulator tests
(tests/engine/test_cuda_simulator.py) check the source's semantics, this one NVVM's code; neither times a GPU.
"""

import re

import numba
import pytest

from numerics import cuda_target


def _nvvm() -> str:
    """Why NVVM cannot compile here ("" if it can)."""
    if numba.config.ENABLE_CUDASIM:
        return "NUMBA_ENABLE_CUDASIM is set: numba.cuda is the simulator, which makes no PTX"
    from numba.cuda.cudadrv import nvvm

    return "" if nvvm.is_available() else "NVVM (the CUDA toolkit's libNVVM) is not installed"


pytestmark = pytest.mark.skipif(bool(_nvvm()), reason=_nvvm() or "NVVM present")


def _counts(ptx: str) -> dict[str, int]:
    return {name: len(re.findall(pattern, ptx)) for name, pattern in (
        ("fma", r"\bfma\.rn\.f64"), ("mul.rn", r"\bmul\.rn\.f64"), ("plain mul/add/sub", r"\b(mul|add|sub)\.f64"),
        ("libdevice call", r"__nv_"))}


def test_a_lane_stage_compiles_without_a_driver_and_without_fused_multiply_adds():
    from numba import cuda, float64, int64

    from twin.engine import plant

    cuda_target.offline()

    def pneumatics(x, c, u, w, dxdt, seal):  # one thread per sample on its column views, as twin.engine.cuda
        i = cuda.grid(1)
        if i < x.shape[1]:
            plant.pneumatics_rhs(x[:, i:i + 1], c[:, i:i + 1], u[:, i:i + 1], w[:, i:i + 1], dxdt[:, i:i + 1], 1,
                                 seal)

    matrix = float64[:, :]
    ptx, _ = cuda.compile_ptx(pneumatics, (matrix, matrix, matrix, matrix, matrix, int64), cc=cuda_target.OFFLINE_CC)
    counts = _counts(ptx)
    # NVVM's default (-fma=1) gives this stage 41 fma.rn.f64 and 88 plain mul.f64 (measured, numba 0.68.1, CUDA 13)
    assert counts["fma"] == 0, counts
    assert counts["plain mul/add/sub"] == 0, counts
    assert counts["mul.rn"] > 50, counts   # the valve and chamber laws' products are there, each rounded
    assert counts["libdevice call"] == 0, counts  # the project's own functions (numerics.elementary), no libdevice


def test_the_target_changes_refuse_an_unknown_numba(monkeypatch):
    import numba.cuda.cudadrv.nvvm as nvvm

    monkeypatch.delattr(nvvm, "compile_ir")
    with pytest.raises(RuntimeError, match="numba.cuda.cudadrv.nvvm.compile_ir"):
        cuda_target.prepare()
