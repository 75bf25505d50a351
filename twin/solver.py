"""``Solver``: how a run is integrated (the method, its step control and its guard), apart from what is run and saved.

As diffrax separates the solver and the step-size controller from the terms and ``SaveAt``, :func:`twin.simulate`
and :func:`twin.simulate_batch` take one ``Solver`` instead of repeating its options in their signatures. It is
checked when it is made: every bad field is named in one :class:`twin.OptionError`, before any run. What it cannot
check alone (a step against the parameter set's loop periods, a method against the fidelity) ``simulate`` checks
with the rest of the request.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields

from twin.engine import group
from twin.engine.integrators import INTEGRATORS
from twin.engine.reference import METHODS as REFERENCE_METHODS
from twin.errors import OptionError
from twin.fidelity import Fidelity

#: The step of the full model [s]: RK4's stability limit along a run with both nuts loaded is 109 us, set by the
#: screw's axial mode (the ``dynamic`` screw-axial level) and, at full fidelity, 122 us by the analog current loop
#: (docs/accuracy.md); 62.5 us divides the drive period.
DEFAULT_DT = 6.25e-5
#: The coarsest step accepted [s]: above 1 ms the position loop's period is missed.
MAX_DT = 1e-3
#: Lanes of a group (:func:`twin.simulate_batch`): a multiple of the vector width (4 doubles with AVX2, 8 with
#: AVX-512), two AVX-512 registers, the campaign's group (``campaigns.bench.adapter.BenchModel.lanes``); faster per
#: sample than 8 (docs/performance.md, "Lanes per group"); the results do not depend on it.
DEFAULT_LANES = 16
#: The engines of the compiled loop: the CPU lane engine, or one run per CUDA thread (:mod:`twin.engine.cuda`).
ENGINES = ("cpu", "cuda")


@dataclass(frozen=True)
class Solver:
    """How :func:`twin.simulate` integrates a run.

    Parameters
    ----------
    integrator : {"rk4", "semi_implicit_euler", "rosenbrock_w2", "imex_euler", "scipy_radau", "scipy_lsoda",
                  "scipy_bdf", "scipy_rk45"}
        A fixed-step method of the compiled loop (default ``"rk4"``) or a ``scipy_*`` adaptive method of the
        reference path (:mod:`twin.engine.reference`), which ignores ``dt``. ``imex_euler`` integrates the screw's
        axial mode implicitly and needs the ``dynamic`` screw-axial level. The name results store as
        ``attrs["integrator"]``, as a campaign spec's ``solver.integrator`` and the CLI's ``--integrator`` do.
    dt : float or None
        Integration step [s] in (0, 1e-3]; it must divide the speed- and position-loop periods and the output
        spacing. Default ``None``: :meth:`step` (RK4 at the 125 us drive period at the campaign's fidelity,
        62.5 us where the screw's axial mode or the analog current loop is modelled).
    rtol : float
        Relative tolerance of the ``scipy_*`` reference path, in [1e-14, 1e-2); default ``1e-10``.
    local_error_guard : bool
        The finite-but-wrong guard (:func:`twin.engine.loop.local_error`), default ``True``; switch it off only to
        demonstrate what it catches.
    lanes : int
        Runs :func:`twin.simulate_batch` advances together in one group (>= 1, default 8); the numbers do not
        depend on it. On the ``cuda`` engine a group is what one call hands the GPU (a thread per run; a group
        larger than the device's memory is split into launches), so thousands, not 8.
    engine : {"cpu", "cuda"}
        Where the compiled loop runs: the CPU lane engine (default) or an NVIDIA GPU, one run per thread
        (:mod:`twin.engine.cuda`, docs/gpu.md: the same bits where no libm function is reached, else within the
        numerical floor). ``cuda`` is refused at once where no GPU and driver are present, and with a ``scipy_*``
        method.

    Raises
    ------
    OptionError
        Naming every bad field at once.
    """

    integrator: str = "rk4"
    dt: float | None = None
    rtol: float = 1e-10
    local_error_guard: bool = True
    lanes: int = DEFAULT_LANES
    engine: str = "cpu"

    def __post_init__(self):
        problems = []
        methods = (*INTEGRATORS, *REFERENCE_METHODS)
        if not (isinstance(self.integrator, str) and self.integrator in methods):
            problems.append(f"integrator: {self.integrator!r} is not one of {', '.join(methods)}")
        if self.dt is not None and not (isinstance(self.dt, (int, float)) and math.isfinite(self.dt)
                                        and 0 < self.dt <= MAX_DT):
            problems.append(f"dt: {self.dt!r} must be None or a step in (0, {MAX_DT:g}] s")
        if not (isinstance(self.rtol, float) and 1e-14 <= self.rtol < 1e-2):
            problems.append(f"rtol: {self.rtol!r} must be a float in [1e-14, 1e-2)")
        if not isinstance(self.local_error_guard, bool):
            problems.append(f"local_error_guard: {self.local_error_guard!r} must be True or False")
        if not (isinstance(self.lanes, int) and not isinstance(self.lanes, bool) and self.lanes >= 1):
            problems.append(f"lanes: {self.lanes!r} must be an int >= 1")
        problems += self._engine_problems()
        if problems:
            raise OptionError(problems)

    def _engine_problems(self) -> list[str]:
        if self.engine not in ENGINES:
            return [f"engine: {self.engine!r} is not one of {', '.join(ENGINES)}"]
        if self.engine == "cpu":
            return []
        if isinstance(self.integrator, str) and self.reference:
            return [f"engine: 'cuda' runs the compiled loop's fixed-step methods, not {self.integrator!r}"]
        from twin.engine.cuda import unavailable

        reason = unavailable()
        return [f"engine: 'cuda' cannot run here: {reason}"] if reason else []

    def group_solver(self):
        """The function that solves a lane group on this engine: :func:`twin.engine.group.solve_group` or
        :func:`twin.engine.cuda.solve_group_cuda` (the same arguments, the same :class:`twin.engine.group.Solved`)."""
        if self.engine == "cuda":
            from twin.engine.cuda import solve_group_cuda

            return solve_group_cuda
        return group.solve_group

    @property
    def reference(self) -> bool:
        """Whether the method is an adaptive one of the reference path (scipy's ``solve_ivp``)."""
        return self.integrator in REFERENCE_METHODS

    def step(self, fidelity: Fidelity | None, drive_period: float) -> float:
        """The step [s] of a run at ``fidelity`` whose drive (speed loop) samples every ``drive_period``.

        The reference path restarts at each drive sample: its grid is the drive period. A given ``dt`` is taken as
        it is. Else RK4 steps at the drive period where neither of the two modes beyond its reach there is modelled
        (the screw's axial mode at the ``quasi_static`` screw-axial level, the analog current loop at the ``ideal``
        current-loop level), and every method at :data:`DEFAULT_DT` otherwise (docs/accuracy.md, "The default"),
        as where the fidelity could not be resolved (``None``: a request refused already, whose step is still
        checked against the loop periods).
        """
        if self.reference:
            return drive_period
        if self.dt is not None:
            return self.dt
        if (self.integrator == "rk4" and fidelity is not None and fidelity.level("screw_axial") == "quasi_static"
                and fidelity.level("current_loop") == "ideal"):
            return drive_period
        return DEFAULT_DT

    def conflicts(self, fidelity: Fidelity) -> list[str]:
        """What the method needs of the model that ``fidelity`` does not give, one problem per line."""
        if self.integrator == "imex_euler" and fidelity.level("screw_axial") != "dynamic":
            return ["integrator: 'imex_euler' integrates the screw's axial mode implicitly and needs "
                    f"fidelity screw_axial = 'dynamic' (the resolved level is {fidelity.level('screw_axial')!r}); "
                    "pass fidelity={'screw_axial': 'dynamic'}"]
        return []


def solver_label(integrator: str, dt: float) -> str:
    """How results, reports and statements name the solver of a run: the method and, for a fixed-step method of the
    compiled loop, its step (``"rk4 at 125 us"``); an adaptive reference method by its name alone."""
    return integrator if integrator in REFERENCE_METHODS or not integrator else f"{integrator} at {dt * 1e6:g} us"


#: The solver of a call that names none: every field at its default.
DEFAULT_SOLVER = Solver()


def split_solver(options: Mapping[str, object]) -> tuple[Solver, dict]:
    """A flat table of run options (a campaign spec's ``solver`` section: ``integrator``, ``dt``, ``output_dt``,
    ``fidelity``) as the :class:`Solver` of those that are its fields and the others, :func:`twin.simulate`'s
    keywords."""
    names = {field.name for field in fields(Solver)}
    return (Solver(**{k: v for k, v in options.items() if k in names}),
            {k: v for k, v in options.items() if k not in names})
