"""numba's CUDA target set up to compile the engine's own ``@njit`` source with the CPU's arithmetic.

A CUDA kernel that calls an ``@njit`` function makes numba recompile it as a device function
(``CUDATypingContext.resolve_value_type``, numba/cuda/target.py), so the lane engine's physics needs no second
copy for the GPU (docs/gpu.md). numba 0.68's built-in ``numba.cuda`` needs four small changes for that source, each
applied here once and checked against the numba internals it relies on (a changed numba fails loudly in
:func:`prepare`, not silently with other numbers):

* **No FMA contraction.** NVVM contracts ``a * b + c`` into ``fma.rn.f64`` by default (``-fma=1``), also without
  fastmath, and ptxas may fuse a ``mul``/``add`` without a rounding modifier. A fused multiply-add rounds once where
  the CPU rounds twice, so the bits would differ. :func:`prepare` passes :data:`NVVM_OPTIONS` to the one NVVM call
  that compiles a kernel's whole module (every device function it reaches): ``-fma=0`` and IEEE division, square
  root and denormals (NVVM's defaults, stated). numba has no public switch for it yet (numba issue #2834,
  numba-cuda PR #839).
* **Varargs overloads.** numba 0.68's ``min``/``max`` are ``@overload`` implementations ``def impl(*x)``, which the
  built-in ``CUDADispatcher.get_call_template`` does not fold ("Signature mismatch: 2 argument types given, but
  function takes 1"); the fold numba-cuda adopted (its PR #160) is applied. The result is compare and select, the
  CPU's semantics.
* **NumPy scalar functions.** ``np.floor`` and ``np.sqrt`` of a float (the instruments' quantisers) have no CUDA
  lowering in numba 0.68; a CUDA-only overload gives ``llvm.floor.f64`` (PTX ``cvt.rmi.f64.f64``, exact; a float,
  so inf and nan stay as on the CPU, unlike ``math.floor``'s int64) and ``math.sqrt`` (``sqrt.rn.f64``, correctly
  rounded as the CPU's ``sqrtsd``). The CPU keeps its own lowering.
* **PTX without a driver** (:func:`offline`, for tests and for a machine without a GPU): a called device function is
  compiled for ``get_current_device().compute_capability`` (numba/cuda/dispatcher.py), which opens a driver
  context even when ``compile_ptx`` is given a ``cc``; a fixed compute capability replaces that one lookup.

Under numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``) kernels run as Python threads on the plain Python
functions, which need none of this: :func:`prepare` does nothing there.
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: Compute capability of PTX made without a driver: Hopper (sm_90), the H200 of issue 43.
OFFLINE_CC = (9, 0)
#: NVVM options of every kernel module (see the module docstring): no FMA contraction, IEEE ``/``, ``sqrt`` and
#: denormals.
NVVM_OPTIONS = {"fma": False, "prec_div": True, "prec_sqrt": True, "ftz": False}

_applied: set[str] = set()


def simulator() -> bool:
    """Whether ``numba.cuda`` is numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``)."""
    return bool(numba.config.ENABLE_CUDASIM)


def unavailable() -> str:
    """Why no CUDA kernel can run here, in one line (``""`` if one can: a GPU with its driver, or the simulator)."""
    from numba import cuda

    if cuda.is_available():
        return ""
    try:
        from numba.cuda.cudadrv.driver import driver

        driver.get_device_count()  # raises the driver's own reason
    except Exception as exc:  # noqa: BLE001 - the driver's reason, whatever its type, is the message
        lines = [line.strip(" :") for line in str(exc).splitlines() if line.strip(" :")]
        reason = " ".join(line for line in lines if not line.startswith(("Error at driver init", "If you are",
                                                                        "try setting", "with the file")))
        return reason or type(exc).__name__
    return "no CUDA GPU found by the driver"


def prepare() -> None:
    """Apply the target changes of the module docstring (once; nothing under the simulator).

    Raises
    ------
    RuntimeError
        If numba's CUDA internals are not those the changes were written for (numba 0.68's built-in
        ``numba.cuda``): the changes must be reviewed, not guessed.
    """
    if simulator():
        return
    _check_internals()
    if "nvvm" not in _applied:
        _no_fma()
    if "fold" not in _applied:
        _fold_varargs()
    if "scalars" not in _applied:
        _numpy_scalars()


def offline(cc: tuple[int, int] = OFFLINE_CC) -> None:
    """:func:`prepare`, and compile device functions for ``cc`` without asking a driver (PTX on a machine without a
    GPU; a kernel launch still needs one)."""
    prepare()
    import numba.cuda.compiler as compiler
    import numba.cuda.dispatcher as dispatcher

    class _Device:
        compute_capability = cc

    dispatcher.get_current_device = compiler.get_current_device = lambda: _Device


def _check_internals() -> None:
    from numba import cuda

    needed = {
        "numba.cuda.cudadrv.nvvm": ("compile_ir",),
        "numba.cuda.dispatcher": ("get_current_device", "CUDADispatcher"),
        "numba.cuda.compiler": ("get_current_device",),
    }
    missing = []
    for name, attributes in needed.items():
        try:
            module = __import__(name, fromlist=["_"])
        except ImportError:
            missing.append(name)
            continue
        missing += [f"{name}.{a}" for a in attributes if not hasattr(module, a)]
    if not cuda.__file__.startswith(numba.__file__.rsplit("/", 1)[0]):
        missing.append(f"numba.cuda is not numba's built-in target ({cuda.__file__})")
    if missing:
        raise RuntimeError(f"numerics.cuda_target: written for numba 0.68's built-in numba.cuda (found numba "
                           f"{numba.__version__}); not found: {', '.join(missing)}. Review the target changes "
                           "(docs/gpu.md) before running the CUDA engine.")


def _no_fma() -> None:
    import numba.cuda.cudadrv.nvvm as nvvm

    original = nvvm.compile_ir

    def compile_ir(llvmir, **opts):
        opts.pop("fastmath", None)  # the project never asks for it; it would switch FMA back on
        opts.update(NVVM_OPTIONS)
        return original(llvmir, **opts)

    nvvm.compile_ir = compile_ir  # numba.cuda.codegen calls it through the module
    _applied.add("nvvm")


def _fold_varargs() -> None:
    from numba.core import typing, utils
    from numba.cuda.dispatcher import CUDADispatcher

    def get_call_template(self, args, kws):
        # numba 0.68's own method with the argument fold of _DispatcherBase.get_call_template
        pysig, args = self._compiler.fold_argument_types(args, kws)
        if self._can_compile:
            self.compile_device(tuple(args))
        template = typing.make_concrete_template(f"CallTemplate({self.py_func.__name__})",
                                                 key=self.py_func.__name__, signatures=self.nopython_signatures)
        return template, utils.pysignature(self.py_func), args, {}

    CUDADispatcher.get_call_template = get_call_template
    _applied.add("fold")


def _numpy_scalars() -> None:
    from llvmlite import ir
    from numba import types
    from numba.core.extending import intrinsic, overload

    @intrinsic
    def float_floor(typingctx, x):
        if not isinstance(x, types.Float):
            return None

        def codegen(context, builder, signature, args):
            function = builder.module.declare_intrinsic("llvm.floor", [ir.DoubleType()])
            return builder.call(function, [context.cast(builder, args[0], signature.args[0], types.float64)])

        return types.float64(x), codegen

    @overload(np.floor, target="cuda")
    def cuda_floor(x):
        if isinstance(x, types.Float):
            return lambda x: float_floor(x)
        return None

    @overload(np.sqrt, target="cuda")
    def cuda_sqrt(x):
        if isinstance(x, types.Float):
            return lambda x: math.sqrt(x)
        return None

    _applied.add("scalars")
