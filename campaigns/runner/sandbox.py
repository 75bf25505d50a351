"""Per-run wall-clock timeout: run each simulation in a killable child process.

A run function may respect ``request.wall_time_limit`` itself, but the bench's
compiled (numba) loop does not return to the interpreter, so neither a signal
handler nor a thread can interrupt it. The only reliable way to stop it is to
kill the process running it. A :class:`Sandbox` is therefore a
long-lived child Python process (one per worker thread) that executes requests
one at a time; the parent waits at most ``wall_time_limit + kill_grace(wall_time_limit)``
seconds for each answer and otherwise kills the child, records a ``"timeout"``
and starts a fresh child for the next run. A child that dies (segfault, out of
memory) yields an ``"error"`` record instead of taking the dask worker down.

What is charged to a run: only the run. A fresh child first unpickles the request
(importing the run function's modules) and calls the run function's warm-up
(:func:`campaigns.runner.runs.warm_up`: e.g. loading numba's compiled loop) and only then
reports ``"started"``; the budget counts from there. Start-up has its own, much
larger limit (:data:`STARTUP_TIMEOUT`), so a killed run does not make the next run
pay for a cold child.

The child is a plain ``subprocess`` (dask worker processes are daemonic and may
not use :mod:`multiprocessing` children). Requests and records travel over
dedicated pipes, so whatever the simulation prints cannot corrupt them. The
child exits when the parent's pipe closes and, on Linux, is also killed if the
parent dies while the child is stuck.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import os
import signal
import subprocess
import sys
import threading
import time
from multiprocessing.connection import Connection

from campaigns.runner.runs import RunModel, RunRequest, execute_group, kill_grace, record, warm_up

#: Seconds a fresh child may take to import and warm up what a request needs (not counted in the
#: run's budget): a cold numba compilation of the bench loop on a loaded machine fits well within it.
STARTUP_TIMEOUT = 600.0


_local = threading.local()
#: The signals that stop a campaign (Ctrl-C, a service's stop): the driver handles them, its children must not.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def children_ignore_stop_signals():
    """Processes started meanwhile ignore Ctrl-C and SIGTERM: the driver alone handles them.

    A terminal's Ctrl-C (and a service's SIGTERM to the process group) reaches every process of the group; the
    dask workers and run sandboxes must not each stop with a traceback, the driver ends them cleanly. A child
    started by this thread inherits its blocked signal mask; in the main thread the signals are also ignored
    process-wide meanwhile, since dask starts its workers from its own threads (an ignored disposition is
    inherited across ``exec``, and Python then leaves it ignored). A Ctrl-C pressed in that window (the
    cluster's start, seconds) is ignored too: press it again once the runs have started.
    """
    previous_mask = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    main = threading.current_thread() is threading.main_thread()
    previous = {sig: signal.signal(sig, signal.SIG_IGN) for sig in STOP_SIGNALS} if main else {}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        signal.pthread_sigmask(signal.SIG_SETMASK, previous_mask)


class Sandbox:
    """A child process executing run requests, killed when one overruns."""

    def __init__(self):
        self._proc: subprocess.Popen | None = None
        self._to_child: Connection | None = None
        self._from_child: Connection | None = None

    def _start(self) -> None:
        child_in, parent_out = os.pipe()
        parent_in, child_out = os.pipe()
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
        with children_ignore_stop_signals():
            self._proc = subprocess.Popen(
                [sys.executable, "-c", f"from campaigns.runner.sandbox import serve; serve({child_in}, {child_out})"],
                pass_fds=(child_in, child_out),
                stdin=subprocess.DEVNULL,
                env=env,
            )
        os.close(child_in)
        os.close(child_out)
        self._to_child = Connection(parent_out, readable=False)
        self._from_child = Connection(parent_in, writable=False)

    def close(self) -> None:
        """Stop the child (kill it if it does not exit on its own)."""
        if self._proc is None:
            return
        self._to_child.close()
        self._from_child.close()
        try:
            self._proc.wait(timeout=2.0)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait()
        self._proc = None

    def _kill(self) -> None:
        self._proc.kill()
        self.close()

    def run(self, run_function: RunModel, request: RunRequest) -> dict:
        """Execute one request in the child; return its record (never raises for run failures)."""
        return self.run_group(run_function, [request])[0]

    def run_group(self, run_function: RunModel, requests: list[RunRequest]) -> list[dict]:
        """Execute requests together in the child (:func:`campaigns.runner.runs.execute_group`); return their records in
        order (never raises for run failures). The group's budget is the sum of its runs' budgets; a group killed
        for overrunning it records every run as a timeout."""
        if self._proc is None or self._proc.poll() is not None:
            self.close()
            self._start()
        self._to_child.send((run_function, requests))
        # The clock starts once the child has unpickled the requests and warmed up
        # (a fresh child's imports and compilation are not the runs' time).
        if not self._from_child.poll(STARTUP_TIMEOUT):
            self._kill()
            return [record(r, "error", f"run process did not start within {STARTUP_TIMEOUT:g} s", float("nan"),
                           float("nan")) for r in requests]
        start = time.perf_counter()
        try:
            message = self._from_child.recv()
        except EOFError:
            return self._died(requests, start)
        if message != "started":
            return [record(r, "error", message, float("nan"), float("nan")) for r in requests]
        budget = sum(r.wall_time_limit for r in requests)
        grace = kill_grace(budget)
        if not self._from_child.poll(budget + grace):
            self._kill()
            elapsed = time.perf_counter() - start
            together = f" with its {len(requests)}-run lane group" if len(requests) > 1 else ""
            reason = f"killed{together} after {elapsed:.3g} s wall clock (budget {budget:g} s + {grace:.3g} s grace)"
            return [record(r, "timeout", reason, float("nan"), elapsed / len(requests)) for r in requests]
        try:
            return self._from_child.recv()
        except EOFError:
            return self._died(requests, start)

    def _died(self, requests: list[RunRequest], start: float) -> list[dict]:
        code = self._proc.wait()
        self.close()
        elapsed = (time.perf_counter() - start) / len(requests)
        return [record(r, "error", f"run process died (exit code {code})", float("nan"), elapsed) for r in requests]


def run_group_isolated(run_function: RunModel, requests: list[RunRequest]) -> list[dict]:
    """Execute ``requests`` together in this thread's :class:`Sandbox` (created on first use)."""
    sandbox = getattr(_local, "sandbox", None)
    if sandbox is None:
        sandbox = _local.sandbox = Sandbox()
        atexit.register(sandbox.close)  # the worker's exit ends its sandbox cleanly
    return sandbox.run_group(run_function, requests)


def _die_with_parent() -> None:
    """Ask Linux to SIGKILL this process when its parent dies (best effort elsewhere)."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def serve(read_fd: int, write_fd: int) -> None:
    """Child side: execute requests from ``read_fd`` and send records to ``write_fd`` until EOF."""
    _die_with_parent()
    requests, records = Connection(read_fd, writable=False), Connection(write_fd, readable=False)
    while True:
        try:
            run_function, group = requests.recv()
        except EOFError:
            return
        except Exception as exc:  # e.g. the run function's module does not import here
            records.send(f"cannot load the request in the run process: {type(exc).__name__}: {exc}")
            continue
        warm_up(run_function, group[0])
        try:
            records.send("started")
            records.send(execute_group(run_function, group))
        except OSError:  # BrokenPipeError: the worker ended this sandbox (a stopped campaign), no traceback
            return
