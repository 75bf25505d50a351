"""Timeout tests under CPU load: how often do they pass on a saturated machine?

Starts CPU-burning processes (one busy loop per core by default: the machine is then at least twice
oversubscribed, as on a CI runner shared with other jobs), then runs the campaign tests that depend on
wall-clock budgets N times, each in a fresh pytest process, and prints the pass count:

* ``test_failed_runs_are_recorded_and_the_campaign_goes_on`` (the timeout test: a hang among healthy
  runs of a 2-worker campaign, 3 s budget),
* ``test_sandbox_survives_a_crash_and_a_hang`` (crash, hang, then a run in a cold child),
* ``test_start_up_is_not_charged_to_the_run`` (a 3 s warm-up against a 1 s budget),
* with ``--with-resume`` also ``test_resume_after_sigkill_reruns_only_unfinished_chunks`` (SIGKILL
  mid-campaign, then resume; it needs the session's reference campaign, about 4x the time).

Usage: python benchmarks/timeout_under_load.py [--repeats 20] [--load N] [--with-resume] [--quick]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TESTS = [
    "tests/campaigns/test_campaign_execution.py::test_failed_runs_are_recorded_and_the_campaign_goes_on",
    "tests/campaigns/test_campaign_execution.py::test_sandbox_survives_a_crash_and_a_hang",
    "tests/campaigns/test_campaign_reliability.py::test_start_up_is_not_charged_to_the_run",
]
RESUME_TEST = "tests/campaigns/test_campaign_resume.py::test_resume_after_sigkill_reruns_only_unfinished_chunks"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=20, help="pytest runs of the timeout tests (default 20)")
    parser.add_argument("--load", type=int, default=os.cpu_count(),
                        help="CPU-burning processes (default: one per core)")
    parser.add_argument("--with-resume", action="store_true", help="also run the SIGKILL-and-resume test")
    parser.add_argument("--quick", action="store_true", help="1 repeat (CI: that it runs; a verdict needs --repeats)")
    args = parser.parse_args()
    repeats = 1 if args.quick else args.repeats
    tests = TESTS + ([RESUME_TEST] if args.with_resume else [])
    print(f"# {platform.machine()}, {os.cpu_count()} cores, load average before: {os.getloadavg()[0]:.2f}; "
          f"{args.load} CPU burner(s); {repeats} repeat(s) of {len(tests)} timeout tests")
    def stop(*_):
        signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a second SIGTERM must not interrupt the clean-up
        sys.exit(143)

    signal.signal(signal.SIGTERM, stop)  # clean up the burners and the tests when terminated
    children = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(args.load)]
    passed = 0
    failures: dict[str, int] = {}
    try:
        for k in range(repeats):
            start = time.monotonic()
            run = subprocess.Popen([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *tests],
                                   cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                   start_new_session=True)
            children.append(run)
            stdout, stderr = run.communicate()
            children.remove(run)
            for name in re.findall(r"^FAILED (\S+)", stdout, flags=re.M):
                failures[name] = failures.get(name, 0) + 1
            ok = run.returncode == 0
            passed += ok
            summary = stdout.strip().splitlines()[-1] if stdout.strip() else stderr[-200:]
            print(f"repeat {k + 1:2d}: {'PASS' if ok else 'FAIL'} in {time.monotonic() - start:5.1f} s, "
                  f"load average {os.getloadavg()[0]:.2f}: {summary}", flush=True)
    finally:
        for child in children:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(child.pid, signal.SIGKILL) if child.args[1] == "-m" else child.kill()
            child.wait()
    print(f"passed {passed}/{repeats} under load")
    for name, count in sorted(failures.items()):
        print(f"  failed {count}x: {name}")
    sys.exit(0 if passed == repeats else 1)


if __name__ == "__main__":
    main()
