"""The queue of a service: campaigns run one at a time, each in a runner subprocess, in submission order.

A runner is a subprocess in its own session (:mod:`app.service.runner`), so that the server's event
loop never waits on a campaign and a cancel or a shutdown stops the runner and every process it
started (dask workers, run sandboxes) with one signal to its process group.

Durability (see ``docs/service.md``): on start, a campaign left ``running`` by a previous server is
either still being run by that server's runner (its lock is held: the executor waits for it) or is
requeued and resumes from its chunk files; queued ones simply run. A graceful shutdown (SIGTERM)
stops the current runner and puts its campaign back in the queue.
"""

from __future__ import annotations

import logging
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from app.service.registry import Registry
from campaigns.runner.storage import LOCK_NAME, CampaignError, OutputLock

#: Seconds a runner gets to exit after SIGTERM before its process group is killed.
STOP_GRACE = 10.0
#: Seconds between two checks of a running campaign (exit, cancel request).
POLL = 0.5
#: Lines of a crashed runner's log quoted in the campaign's error.
LOG_TAIL = 15

_log = logging.getLogger("benchtwin.service")


class Executor:
    """Runs the registry's queued campaigns, one at a time, in a background thread.

    Parameters
    ----------
    registry : Registry
    workers : int
        Worker processes of each campaign's local dask cluster.
    scheduler : str, optional
        Address of an existing dask scheduler (instead of a local cluster per campaign).
    """

    def __init__(self, registry: Registry, workers: int = 2, scheduler: str | None = None):
        self.registry = registry
        self.workers = workers
        self.scheduler = scheduler
        self._wake = threading.Event()
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="benchtwin-executor", daemon=True)

    def start(self) -> None:
        """Requeue what a previous server left running, then start working through the queue."""
        for campaign_id in self.registry.ids_in_state("running"):
            if _runner_pid(self.registry.campaign_dir(campaign_id)) is None:
                self.registry.transition(campaign_id, ("running",), state="queued", stage="requeued",
                                         stage_message="interrupted (server stopped); resumes from its chunk files")
                _log.info("campaign %s requeued: it resumes from its chunk files", campaign_id)
        self._thread.start()

    def stop(self) -> None:
        """Stop the current runner (its campaign goes back to the queue) and the thread."""
        self._stopping.set()
        self._wake.set()
        self._thread.join(timeout=STOP_GRACE + 20)

    def notify(self) -> None:
        """Something was queued or a cancel was requested."""
        self._wake.set()

    def cancel(self, campaign_id: str) -> str:
        """Cancel a queued or running campaign; the state it is in afterwards (or was in, if final)."""
        if self.registry.transition(campaign_id, ("queued",), state="cancelled", finished_at=time.time(),
                                    stage="cancelled", stage_message=""):
            return "cancelled"
        if self.registry.transition(campaign_id, ("running",), cancel_requested=1):
            self._wake.set()
            return "cancelling"
        return self.registry.campaign(campaign_id)["state"]

    # --- the thread

    def _loop(self) -> None:
        while not self._stopping.is_set():
            try:
                running = self.registry.ids_in_state("running")
                if running:  # a runner of a previous server, still alive (start() requeued the others)
                    self._wait_for_orphan(running[0])
                    continue
                queued = self.registry.ids_in_state("queued")
                if not queued:
                    self._wake.wait(timeout=5.0)
                    self._wake.clear()
                    continue
                self._run(queued[0])
            except Exception:  # the queue must outlive any one campaign's trouble
                _log.exception("executor error; retrying in 5 s")
                self._stopping.wait(5.0)

    def _run(self, campaign_id: str) -> None:
        now = time.time()
        record = self.registry.campaign(campaign_id)
        if not self.registry.transition(campaign_id, ("queued",), state="running",
                                        started_at=record["started_at"] or now,
                                        stage="starting", stage_message="starting the runner"):
            return  # cancelled in the meantime
        campaign_dir = self.registry.campaign_dir(campaign_id)
        command = [sys.executable, "-m", "app.service.runner", str(self.registry.data), campaign_id,
                   "--workers", str(self.workers)] + (["--scheduler", self.scheduler] if self.scheduler else [])
        _log.info("campaign %s: runner started", campaign_id)
        with open(campaign_dir / "runner.log", "ab") as log:
            process = subprocess.Popen(command, cwd=campaign_dir, stdin=subprocess.DEVNULL, stdout=log,
                                       stderr=subprocess.STDOUT, start_new_session=True)
        while process.poll() is None:
            self._wake.wait(timeout=POLL)
            self._wake.clear()
            if self._stopping.is_set():
                _stop_group(process.pid, process)
                self.registry.transition(campaign_id, ("running",), state="queued", stage="requeued",
                                         stage_message="interrupted (server stopped); resumes from its chunk files")
                return
            if self.registry.campaign(campaign_id)["cancel_requested"]:
                _stop_group(process.pid, process)
        self._settle(campaign_id, process.returncode)

    def _wait_for_orphan(self, campaign_id: str) -> None:
        campaign_dir = self.registry.campaign_dir(campaign_id)
        pid = _runner_pid(campaign_dir)
        while pid is not None and not self._stopping.is_set():
            if self.registry.campaign(campaign_id)["cancel_requested"]:
                _stop_group(pid)
            self._wake.wait(timeout=POLL)
            self._wake.clear()
            pid = _runner_pid(campaign_dir)
        if pid is None:
            self._settle(campaign_id, None)

    def _settle(self, campaign_id: str, returncode: int | None) -> None:
        """Record the outcome of a runner that ended without recording it (killed, crashed, cancelled)."""
        record = self.registry.campaign(campaign_id)
        if record["state"] != "running":
            _log.info("campaign %s: %s", campaign_id, record["state"])
            return
        if record["cancel_requested"]:
            self.registry.transition(campaign_id, ("running",), state="cancelled", stage="cancelled", stage_message="",
                                     finished_at=time.time())
            _log.info("campaign %s: cancelled", campaign_id)
            return
        tail = _log_tail(self.registry.campaign_dir(campaign_id) / "runner.log")
        how = "was killed or lost" if returncode is None or returncode < 0 else f"exited with status {returncode}"
        self.registry.transition(campaign_id, ("running",), state="failed", finished_at=time.time(),
                                 error=f"the runner {how} without recording an outcome; "
                                       f"last lines of runner.log:\n{tail}")
        _log.warning("campaign %s: runner %s", campaign_id, how)


def _runner_pid(campaign_dir: Path) -> int | None:
    """Pid of the live runner holding ``campaign_dir``'s lock, or ``None`` if no runner holds it."""
    try:
        OutputLock(campaign_dir).acquire().release()
        return None
    except CampaignError:
        text = (campaign_dir / LOCK_NAME).read_text(errors="replace")
        found = re.match(r"pid (\d+)", text)
        return int(found.group(1)) if found else None


def _stop_group(pgid: int, process: subprocess.Popen | None = None) -> None:
    """SIGTERM to a runner's process group; SIGKILL to what is left after ``STOP_GRACE``."""
    try:
        os.killpg(pgid, signal.SIGTERM)
    except ProcessLookupError:
        return
    deadline = time.monotonic() + STOP_GRACE
    while time.monotonic() < deadline:
        if process is not None and process.poll() is not None:
            break
        time.sleep(0.2)
    try:
        os.killpg(pgid, signal.SIGKILL)  # the dask workers and sandboxes the runner leaves behind, if any
    except ProcessLookupError:
        pass
    if process is not None:
        process.wait()


def _log_tail(path: Path) -> str:
    try:
        return "\n".join(path.read_text(errors="replace").splitlines()[-LOG_TAIL:])
    except OSError:
        return "(no runner.log)"
