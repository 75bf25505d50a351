"""The subprocess that runs one campaign of the service: ``python -m app.service.runner DATA ID``.

It calls :func:`app.pipeline.run_campaign_pipeline` (what ``twin campaign run --analyze --report``
calls) with ``resume=True``: a campaign interrupted by a stopped or killed server continues from its
chunk files, re-running only the runs without a record. The runner records in the registry the stage
(from the pipeline's announcements), the progress (read from the chunk files every
``PROGRESS_PERIOD`` seconds), and at the end the state and the verdict statements of the analysis,
verbatim as :func:`campaigns.analysis.campaign_analysis.summary` words them, with the report's page-1 figure of each
fault sweep (:func:`reports.detection.detection_answer`) drawn beside the results and listed with its caption, for the
campaign page.

It holds ``campaigns/<id>/.lock`` (:class:`campaigns.runner.storage.OutputLock`) for its whole life: a
restarted server that finds the lock held knows this runner outlived the old server and waits for it
instead of starting a second one.
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
import traceback
from collections import Counter
from pathlib import Path

import numpy as np
import xarray as xr

from app.pipeline import run_campaign_pipeline
from app.service.registry import Registry
from app.service.submission import answer_figure_name, load_frozen, output_dir
from campaigns.analysis.campaign_analysis import summary
from campaigns.runner.files import CampaignInterrupted
from campaigns.runner.storage import CampaignError, OutputLock
from reports.detection import detection_answer, sweep_views
from reports.errors import ReportError
from twin.errors import InputError

#: Seconds between two scans of the chunk files.
PROGRESS_PERIOD = 1.0
#: Failed runs listed with their reason (the counts cover all of them).
FAILURE_EXAMPLES = 20
#: Exit status when another runner holds the campaign (the executor then waits for that one).
EXIT_BUSY = 75


class Progress:
    """Runs recorded so far in a campaign's chunk files, read incrementally (each file once)."""

    def __init__(self, chunk_dir: Path, datasets: list[str]):
        self.chunk_dir = chunk_dir
        self.datasets = datasets
        self.seen: set[str] = set()
        self.done = 0
        self.failures: Counter = Counter()
        self.examples: list[dict] = []

    def scan(self) -> bool:
        """Read new chunk files; whether anything changed."""
        changed = False
        for path in sorted(self.chunk_dir.glob("d*.npz")):  # complete files only: chunks are moved into place
            if path.name in self.seen:
                continue
            with np.load(path, allow_pickle=False) as chunk:
                dataset, runs = int(chunk["dataset_index"]), chunk["run"]
                status, reasons = chunk["status"], chunk["failure_reason"]
            self.seen.add(path.name)
            self.done += len(runs)
            for run, state, reason in zip(runs, status, reasons, strict=True):
                if state != "ok":
                    self.failures[str(state)] += 1
                    if len(self.examples) < FAILURE_EXAMPLES:
                        self.examples.append({"dataset": self.datasets[dataset], "run": int(run),
                                              "status": str(state), "reason": str(reason)})
            changed = True
        return changed


def _watch(registry: Registry, campaign_id: str, progress: Progress, stop: threading.Event) -> None:
    while True:
        finished = stop.wait(PROGRESS_PERIOD)
        if progress.scan():
            registry.update(campaign_id, runs_done=progress.done, failures=dict(progress.failures),
                            failure_examples=progress.examples)
        if finished:
            return


def run(data: Path, campaign_id: str, workers: int, scheduler: str | None) -> int:
    """Run campaign ``campaign_id`` of data directory ``data`` to its end; the exit status."""
    registry = Registry(data)
    campaign_dir = registry.campaign_dir(campaign_id)
    try:
        lock = OutputLock(campaign_dir).acquire()
    except CampaignError as exc:
        print(f"runner: {exc}", flush=True)
        return EXIT_BUSY
    try:
        record = registry.campaign(campaign_id)
        registry.update(campaign_id, legs=record["legs"] + 1, stage="starting", stage_message="loading the spec")
        spec = load_frozen(campaign_dir)
        out = output_dir(campaign_dir)
        progress = Progress(out / "chunks" / spec.spec_hash()[:16], [d.name for d in spec.datasets])
        stop = threading.Event()
        watcher = threading.Thread(target=_watch, args=(registry, campaign_id, progress, stop), daemon=True)
        watcher.start()

        def announce(stage: str, message: str) -> None:
            print(f"[{time.strftime('%H:%M:%S')}] {stage}: {message}", flush=True)
            registry.update(campaign_id, stage=stage, stage_message=message)

        try:
            outputs = run_campaign_pipeline(spec, out, workers=workers, scheduler=scheduler, resume=True,
                                            progress=False, announce=announce)
        finally:
            stop.set()
            watcher.join()
        with xr.open_dataset(outputs.analysis, engine="netcdf4") as analysis:
            statements, warnings = summary(analysis)
            figures = answer_figures(analysis, out)
        registry.transition(campaign_id, ("running",), state="done", stage="done", stage_message="",
                            finished_at=time.time(),
                            summary={"statements": statements, "warnings": warnings, "figures": figures})
        print(f"[{time.strftime('%H:%M:%S')}] done", flush=True)
        return 0
    except CampaignInterrupted as stop:  # the executor's SIGTERM (cancel, server stop): it records the outcome
        print(f"[{time.strftime('%H:%M:%S')}] {stop}", flush=True)
        return 143
    except (InputError, CampaignError, ReportError) as exc:  # the user's to fix: one message, as the CLI prints it
        print(f"runner: {exc}", flush=True)
        registry.transition(campaign_id, ("running",), state="failed", error=str(exc), finished_at=time.time())
        return 1
    except Exception as exc:
        traceback.print_exc()
        registry.transition(campaign_id, ("running",), state="failed", finished_at=time.time(),
                            error=f"internal error: {type(exc).__name__}: {exc} (traceback in runner.log)")
        return 1
    finally:
        lock.release()


def answer_figures(analysis: xr.Dataset, out: Path) -> list[dict[str, str]]:
    """Draw the report's page-1 figure of each fault sweep into ``out`` (``detection.png`` for the first,
    :func:`app.service.submission.answer_figure_name`); ``{"name", "caption"}`` of each, in the sweeps' order, empty
    when the analysis has no sweep (then no file). Each is moved into place whole, so the page never serves half a
    file."""
    figures = []
    for key, view in sweep_views(analysis):
        answer = detection_answer(view)
        if answer is None:
            continue
        png, caption = answer
        name = answer_figure_name(key)
        partial = out / f"{name}.partial"
        partial.write_bytes(png)
        os.replace(partial, out / name)
        figures.append({"name": name, "caption": caption})
    return figures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m app.service.runner", description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("campaign_id")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--scheduler")
    args = parser.parse_args(argv)
    return run(args.data, args.campaign_id, args.workers, args.scheduler)


if __name__ == "__main__":
    sys.exit(main())
