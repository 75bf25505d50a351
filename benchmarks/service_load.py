"""Load test of ``twin serve``: N concurrent clients poll a campaign's status and the campaign list while it runs.

Usage::

    python benchmarks/service_load.py                 # 20 clients for 30 s (the issue's figure)
    python benchmarks/service_load.py --quick         # 5 clients for 5 s
    python benchmarks/service_load.py --clients 40 --seconds 60

Bounded and local: the server is started here, on a free loopback port, with a fresh data directory
in a temporary folder; it runs a small thesis campaign (``tests/service/small_thesis.toml``, data sets
2 and 4) while the clients poll, then the campaign is cancelled and the server stopped. Each client
alternates ``GET /api/v1/campaigns/{id}`` and ``GET /api/v1/campaigns``, back to back. Printed: requests,
errors (non-200 answers and transport errors), throughput, p50/p95/p99/max latency, and whether the
campaign was running through the whole window. The clients run in this process's threads, on the same
cores as the server and the campaign: the latencies include that contention.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from importlib import metadata
from pathlib import Path

import httpx
from machine import header

from app.service.auth import create_token
from app.service.registry import Registry

SPEC = Path(__file__).resolve().parents[1] / "tests" / "service" / "small_thesis.toml"
SERVICE_PACKAGES = ("fastapi", "starlette", "uvicorn", "httpx")
START_BUDGET = 600.0
RUNNING_BUDGET = 1800.0


def free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(predicate, budget: float, what: str) -> None:
    deadline = time.monotonic() + budget
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.5)
    raise SystemExit(f"service_load: {what} not reached within {budget:.0f} s")


def poll(url: str, token: str, campaign_id: str, until: float, latencies: list, errors: list) -> None:
    with httpx.Client(base_url=url, headers={"Authorization": f"Bearer {token}"}, timeout=60) as api:
        paths = (f"/api/v1/campaigns/{campaign_id}", "/api/v1/campaigns")
        k = 0
        while time.monotonic() < until:
            path = paths[k % 2]
            k += 1
            start = time.perf_counter()
            try:
                response = api.get(path)
                elapsed = time.perf_counter() - start
                if response.status_code != 200:
                    errors.append(f"{path}: HTTP {response.status_code}")
                latencies.append(elapsed)
            except httpx.HTTPError as exc:
                errors.append(f"{path}: {type(exc).__name__}: {exc}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clients", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--runs", type=int, default=12, help="runs per data set of the campaign (default 12)")
    parser.add_argument("--quick", action="store_true", help="5 clients for 5 s")
    args = parser.parse_args()
    if args.quick:
        args.clients, args.seconds, args.runs = 5, 5.0, 4
    header(f"service load: {args.clients} clients polling status and list for {args.seconds:.0f} s", args.quick)
    print("# " + "; ".join(f"{name} {metadata.version(name)}" for name in SERVICE_PACKAGES), flush=True)

    with tempfile.TemporaryDirectory(prefix="benchtwin-service-load-") as tmp:
        data = Path(tmp) / "data"
        registry = Registry(data)
        reader, submitter, admin = (create_token(registry, role, role) for role in ("read", "submit", "admin"))
        url = f"http://127.0.0.1:{free_port()}"
        log = open(Path(tmp) / "server.log", "wb")
        server = subprocess.Popen([sys.executable, "-m", "app.cli", "serve", "--data", str(data),
                                   "--port", url.rsplit(":", 1)[1], "--workers", "1"],
                                  stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            probe = httpx.Client(base_url=url, timeout=30)

            def healthy() -> bool:
                try:
                    return probe.get("/health").status_code == 200
                except httpx.TransportError:
                    return False

            wait_for(healthy, START_BUDGET, "the server's /health")
            response = probe.post("/api/v1/campaigns", content=SPEC.read_text(), params={"runs": args.runs},
                                  headers={"Authorization": f"Bearer {submitter}"})
            response.raise_for_status()
            campaign_id = response.json()["id"]

            def state() -> dict:
                answer = probe.get(f"/api/v1/campaigns/{campaign_id}", headers={"Authorization": f"Bearer {reader}"})
                return answer.json()

            wait_for(lambda: state()["stage"] in ("runs", "analysis", "report"), RUNNING_BUDGET,
                     "the campaign's run stage")
            before = state()
            latencies: list[float] = []
            errors: list[str] = []
            until = time.monotonic() + args.seconds
            threads = [threading.Thread(target=poll, args=(url, reader, campaign_id, until, latencies, errors))
                       for _ in range(args.clients)]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            after = state()
            probe.post(f"/api/v1/campaigns/{campaign_id}/cancel", headers={"Authorization": f"Bearer {admin}"})
            probe.close()
        finally:
            server.terminate()
            try:
                server.wait(timeout=120)
            except subprocess.TimeoutExpired:
                server.kill()
            log.close()

    if not latencies:
        print("no request completed")
        return 1
    q = statistics.quantiles(latencies, n=100)
    print(f"campaign {campaign_id}: {before['state']} ({before['stage']}, {before['progress']['runs_done']}/"
          f"{before['progress']['runs_total']} runs) at the start of the window, {after['state']} ({after['stage']}, "
          f"{after['progress']['runs_done']}/{after['progress']['runs_total']} runs) at its end")
    print(f"requests: {len(latencies)} in {args.seconds:.0f} s ({len(latencies) / args.seconds:.0f}/s) by "
          f"{args.clients} clients; errors: {len(errors)}")
    print(f"latency: p50 {q[49] * 1e3:.1f} ms, p95 {q[94] * 1e3:.1f} ms, p99 {q[98] * 1e3:.1f} ms, "
          f"max {max(latencies) * 1e3:.1f} ms")
    for line in sorted(set(errors))[:10]:
        print(f"  error: {line}")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
