"""A real ``twin serve`` in a subprocess on a free loopback port, the application in this process for the probes
that run nothing, and what the service tests need around them.

Budgets are wide on purpose (the CI machine has 2 shared cores; a cold numba compile takes minutes
under load): a budget only bounds a hung test, no assertion depends on how fast anything is.
"""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time
import warnings
from pathlib import Path

import httpx
import psutil

from app.service.auth import create_token as create_token_record
from app.service.server import Settings, create_app

with warnings.catch_warnings():  # Starlette asks for httpx2, which the lock does not hold; httpx still works
    warnings.filterwarnings("ignore", "Using `httpx` with `starlette.testclient` is deprecated")
    from fastapi.testclient import TestClient

#: Seconds a server gets to answer /health after start (imports, registry) and a campaign to finish.
START_BUDGET = 600.0
CAMPAIGN_BUDGET = 3600.0
SPEC = Path(__file__).with_name("small_thesis.toml")
FINAL = ("done", "failed", "cancelled")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def twin(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "app.cli", *args], capture_output=True, text=True, timeout=1800)


def create_token(data: Path, name: str, role: str) -> str:
    result = twin("serve", "token", "create", name, "--role", role, "--data", str(data))
    assert result.returncode == 0, result.stderr
    return result.stdout.strip().splitlines()[-1]


class Server:
    """``twin serve --data DATA`` on a free port; ``log`` collects everything it prints."""

    def __init__(self, data: Path, log: Path, workers: int = 1):
        self.data, self.log_path, self.workers = data, log, workers
        self.process: subprocess.Popen | None = None
        self.clients: dict[str | None, httpx.Client] = {}
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"

    def start(self) -> Server:
        with open(self.log_path, "ab") as log:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "app.cli", "serve", "--data", str(self.data), "--port", str(self.port),
                 "--workers", str(self.workers)],
                stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        deadline = time.monotonic() + START_BUDGET
        while time.monotonic() < deadline:
            assert self.process.poll() is None, f"the server exited:\n{self.log()}"
            try:
                with httpx.Client(timeout=5) as probe:
                    if probe.get(f"{self.url}/health").status_code == 200:
                        return self
            except httpx.TransportError:
                pass
            time.sleep(0.5)
        raise AssertionError(f"the server did not answer /health within {START_BUDGET} s:\n{self.log()}")

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def tree(self) -> list[psutil.Process]:
        """The server and every process below it (runner, dask workers, sandboxes)."""
        root = psutil.Process(self.process.pid)
        return [root, *root.children(recursive=True)]

    def kill9(self) -> None:
        """SIGKILL to the server and everything it started, at once (as when its service or container is killed)."""
        processes = self.tree()
        for p in processes:
            p.suspend()  # freeze all first, so nothing moves on while the others are being killed
        for p in processes:
            p.kill()
        psutil.wait_procs(processes, timeout=60)
        self.process.wait()

    def stop(self) -> None:
        """SIGTERM (graceful); whatever is left after the budget is killed."""
        for api in self.clients.values():
            api.close()
        self.clients.clear()
        if self.process is None or self.process.poll() is not None:
            return
        leftovers = self.tree()
        self.process.send_signal(signal.SIGTERM)
        try:
            self.process.wait(timeout=120)
        except subprocess.TimeoutExpired:
            pass
        for p in leftovers:
            try:
                p.kill()
            except psutil.NoSuchProcess:
                pass
        self.process.wait()


def client(server: Server, token: str | None) -> httpx.Client:
    """The server's HTTP client for ``token`` (one per token, closed when the server stops)."""
    if token not in server.clients:
        headers = {"Authorization": f"Bearer {token}"} if token else {}
        server.clients[token] = httpx.Client(base_url=server.url, headers=headers, timeout=120)
    return server.clients[token]


def submit(api: httpx.Client, runs: int) -> dict:
    """Submit the test spec with ``runs`` per data set; the accepted campaign's record (201 asserted)."""
    response = api.post("/api/v1/campaigns", content=SPEC.read_text(), params={"runs": runs})
    assert response.status_code == 201, response.text
    return response.json()


def wait_until(predicate, budget: float = CAMPAIGN_BUDGET, period: float = 0.5, what: str = "condition"):
    """Poll ``predicate()`` until it returns something truthy; that value."""
    deadline = time.monotonic() + budget
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(period)
    raise AssertionError(f"{what} not reached within {budget} s")


def wait_final(api: httpx.Client, campaign_id: str) -> dict:
    def final():
        record = api.get(f"/api/v1/campaigns/{campaign_id}").json()
        return record if record["state"] in FINAL else None

    return wait_until(final, what=f"a final state of campaign {campaign_id}")


def chunk_runs(out: Path) -> list[tuple[int, int]]:
    """``(dataset, run)`` of every run recorded in the chunk files of an output directory (repeats kept)."""
    import numpy as np

    runs = []
    for path in sorted(out.glob("chunks/*/d*.npz")):
        with np.load(path) as chunk:
            runs += [(int(chunk["dataset_index"]), int(r)) for r in chunk["run"]]
    return runs



class LocalService:
    """The application in this process (no executor: what is queued stays queued), for the probes that need no
    campaign to run; ``client(name, role)`` is a test client with that user's token (created on first use)."""

    def __init__(self, data: Path, **settings):
        self.app = create_app(Settings(data=data, start_executor=False, **settings))
        self.registry = self.app.state.registry
        self.tokens: dict[str, str] = {}

    def client(self, name: str | None = None, role: str = "submit", **headers) -> TestClient:
        if name is not None:
            if name not in self.tokens:
                self.tokens[name] = create_token_record(self.registry, name, role)
            headers = {"Authorization": f"Bearer {self.tokens[name]}", **headers}
        return TestClient(self.app, headers=headers, follow_redirects=False)

    def campaign_ids(self) -> list[str]:
        """Every campaign recorded (any state)."""
        return [r["id"] for r in self.registry.campaigns(limit=10**6)]
