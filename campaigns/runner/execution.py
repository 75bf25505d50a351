"""Running a campaign on dask.distributed.

Runs are grouped into chunks (one dask task each, all from one data set). The
driver keeps ``2 x`` the number of worker threads of chunks in flight, writes
each finished chunk (:mod:`campaigns.runner.storage`) and submits the next one.

Chunk size rule
---------------
Unless the spec fixes ``execution.chunk_size``, the first chunks hold one run
each (the pilot); afterwards the median measured run time ``T`` sets

``c = ceil(TASK_OVERHEAD / (OVERHEAD_TARGET * T))``

so that the per-task overhead (scheduling, transfer of the chunk, the driver's
chunk write; ``TASK_OVERHEAD`` is a measured upper value, see
``benchmarks/campaign_throughput.py``) stays below 5 % of the compute. ``c`` is
capped so that (i) every worker thread still gets ``BALANCE_CHUNKS`` chunks of
what remains (load balance, progress granularity) and (ii) a chunk holds at most
``MAX_CHUNK_SECONDS`` of work (what a killed driver loses). Chunking never
changes results: every run is stateless (:mod:`campaigns.runner.sampling`).

Failure semantics
-----------------
A run that raises, diverges, returns NaN or exceeds its wall-clock budget is a
record with a status and a reason (:mod:`campaigns.runner.runs`, :mod:`campaigns.runner.sandbox`);
the campaign goes on. Only infrastructure failures — a lost worker
(``KilledWorker``) or a broken connection (``CommClosedError``/``OSError`` from
the comm layer) — are retried, ``MAX_RETRIES`` times; a chunk still failing
after that is recorded with status ``"lost"``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import logging
import math
import os
import signal
import statistics
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Collection
from pathlib import Path

from distributed import Client, LocalCluster, WorkerPlugin, as_completed
from distributed.comm.core import CommClosedError
from distributed.scheduler import KilledWorker
from tqdm.auto import tqdm

from campaigns.runner.budget import check_disk, estimate
from campaigns.runner.files import CampaignError, CampaignInterrupted
from campaigns.runner.provenance import provenance
from campaigns.runner.runs import RunModel, RunRequest, execute_group, record, run_function_name
from campaigns.runner.sampling import sample
from campaigns.runner.sandbox import STOP_SIGNALS, Sandbox, children_ignore_stop_signals, run_group_isolated
from campaigns.runner.spec import BOUNDS, CampaignSpec
from campaigns.runner.storage import ChunkStore, OutputLock
from twin.scenes import split_targets

#: Per-task overhead [s]: dask round trip, sandbox pipes and the driver's chunk write; an upper value of the
#: measured one (docs/performance.md, "The figures behind the campaign code's constants").
TASK_OVERHEAD = 0.02
#: Largest fraction of the compute time the per-task overhead may take.
OVERHEAD_TARGET = 0.05
#: Chunks per worker thread kept available for load balancing.
BALANCE_CHUNKS = 4
#: Most work [s] put in one chunk.
MAX_CHUNK_SECONDS = 60.0
#: Resubmissions of a chunk after an infrastructure failure.
MAX_RETRIES = 2
INFRASTRUCTURE_ERRORS = (KilledWorker, CommClosedError, OSError)


def chunk_size(run_time: float | None, remaining: int, slots: int) -> int:
    """Number of runs in the next chunk (see the module docstring).

    Parameters
    ----------
    run_time : float or None
        Median wall time of one run so far [s]; ``None`` before any is known (pilot: 1).
    remaining : int
        Runs not yet submitted.
    slots : int
        Worker threads.
    """
    if run_time is None:
        return 1
    per_run = max(run_time, 1e-9)
    overhead_bound = math.ceil(TASK_OVERHEAD / (OVERHEAD_TARGET * per_run))
    balance_bound = math.ceil(remaining / (BALANCE_CHUNKS * slots))
    duration_bound = math.floor(MAX_CHUNK_SECONDS / per_run)
    return max(1, min(overhead_bound, balance_bound, duration_bound))


def run_chunk(run_function: RunModel, requests: list[RunRequest], isolation: str) -> list[dict]:
    """Dask task: execute the runs of one chunk, in lane groups of ``run_function.lanes`` where the run function
    takes groups (:func:`campaigns.runner.runs.execute_group`), and return their records in order."""
    lanes = run_function.lanes
    run = run_group_isolated if isolation == "process" else execute_group
    return [record for first in range(0, len(requests), lanes)
            for record in run(run_function, requests[first:first + lanes])]


def build_request(spec: CampaignSpec, samples, dataset_index: int, run_index: int, *,
                  targets: list[str] | None = None) -> RunRequest:
    """The request of run ``run_index`` of data set ``dataset_index``.

    ``samples`` is the array of :func:`campaigns.runner.sampling.sample`; sampled
    ``scene.*`` targets become scene conditions, the others parameter values,
    with the data set's fixed ``parameters``.
    ``targets`` names the sampled columns (default: the spec's resolved table;
    :mod:`campaigns.bench.replay` passes those stored in ``results.nc``).
    """
    dataset = spec.datasets[dataset_index]
    targets = [d.target for d in spec.distributions()] if targets is None else targets
    sampled, parameter_values = split_targets(
        {target: float(value) for target, value in zip(targets, samples[dataset_index, run_index], strict=False)})
    conditions = {**dataset.conditions, **sampled}
    parameter_values = {**dataset.parameters, **parameter_values}  # a fixed sampled column holds its fixed value
    traced = run_index < spec.traces.runs_per_dataset
    return RunRequest(
        dataset=dataset.name,
        dataset_index=dataset_index,
        run_index=run_index,
        scene=dataset.scene or spec.base.scene,
        parameters=spec.base.parameters,
        conditions=conditions,
        parameter_values=parameter_values,
        root_seed=spec.root_seed,
        # a data set's own levels (one fidelity across a fault sweep: campaigns.bench.campaign.sweep_fidelity); a
        # "full" campaign (the fidelity audit's) keeps its full levels
        solver={**spec.solver.model_dump(),
                **({"fidelity": dataset.fidelity} if dataset.fidelity is not None and spec.solver.fidelity != "full"
                   else {})},
        features=tuple(spec.features),
        trace_variables=tuple(spec.traces.variables) if traced else (),
        outputs=tuple(spec.features) + (tuple(spec.traces.variables) if spec.traces.runs_per_dataset else ()),
        trace_decimation=spec.traces.decimation,
        wall_time_limit=spec.execution.timeout,
        seed_index=spec.seed_index(dataset_index),
        procedure=dict(dataset.procedure),
    )


class _QuietStop:
    """Silences logging from the moment a stop (Ctrl-C, SIGTERM: ``KeyboardInterrupt`` in the driver) unwinds the
    cluster's context until the client and the cluster are closed (:func:`_run`).

    Closing them with runs in flight cancels tasks and ends workers mid-run, and dask and its event loop log that at
    ERROR with tracebacks (a comm closed, a heartbeat failed, a task destroyed while pending), timing-dependent, before
    the runner's one line: they tell the user nothing, who asked for the stop. Only the signal path is silenced (a
    failure keeps its logs), and only for the seconds of the close; the client is closed before the cluster
    (:func:`_client`), so no client waits on a scheduler already gone.
    """

    def __init__(self):
        self._previous: int | None = None

    def on_exit(self, exc_type, exc, tb) -> bool:
        if exc_type is not None and issubclass(exc_type, (KeyboardInterrupt, CampaignInterrupted)) \
                and self._previous is None:
            self._previous = logging.root.manager.disable
            logging.disable(logging.CRITICAL)
        return False  # the stop goes on unwinding

    def restore(self) -> None:
        if self._previous is not None:
            logging.disable(self._previous)
            self._previous = None


@contextlib.contextmanager
def _client(workers: int, scheduler: str | None):
    """A client of ``scheduler``, or of a local cluster of ``workers`` processes; on exit the client closes first."""
    if scheduler is not None:
        with Client(scheduler) as client:
            yield client
        return
    # silence_logs: the nanny's shutdown warnings (a worker killed after its grace period) are not the user's business
    with LocalCluster(
        n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.ERROR
    ) as cluster, Client(cluster) as client:
        client.register_plugin(QuietWorkerClose())  # this campaign's own workers only, never a shared scheduler's
        yield client


class Cluster:
    """The dask client of one or more campaigns: started when a campaign first needs it, closed when the ``with``
    block ends (the client first, then a local cluster; a stop by Ctrl-C or SIGTERM silences that close:
    :class:`_QuietStop`).

    :func:`run_campaign` opens its own unless it is given one; the bench's campaign passes one to its runs and to its
    fidelity audit (:func:`campaigns.bench.campaign.run_campaign`), so that the audit's runs go to the workers that
    already hold the compiled model instead of starting and compiling again.
    """

    def __init__(self, workers: int, scheduler: str | None = None,
                 announce: Callable[[str, str], None] | None = None):
        self.workers, self.scheduler = workers, scheduler
        self.announce = announce or (lambda stage, message: None)
        self._stack = contextlib.ExitStack()
        self._client: Client | None = None
        self._name = ""

    @property
    def started(self) -> bool:
        """Whether the client is up (its workers then hold the model a campaign compiled before they started)."""
        return self._client is not None

    @property
    def slots(self) -> int:
        """Worker threads a campaign's estimate assumes: the local workers, one for a scheduler's unknown cluster."""
        return 1 if self.scheduler else self.workers

    def client(self, name: str) -> Client:
        """The client, started on the first call (announced as ``cluster start`` for campaign ``name``)."""
        if self._client is None:
            self._name = name
            quiet = _QuietStop()
            self._stack.callback(quiet.restore)  # last: once the client and the cluster are closed
            self.announce("cluster start", f"{name}: starting "
                          f"{'the client' if self.scheduler else f'{self.workers} worker processes'} (seconds: "
                          "docs/performance.md)")
            with children_ignore_stop_signals():  # the workers (and their sandboxes) leave Ctrl-C to the driver
                self._client = self._stack.enter_context(_client(self.workers, self.scheduler))
            self._stack.push(quiet.on_exit)  # first: a stop silences the close that follows
        return self._client

    def __enter__(self) -> Cluster:
        return self

    def __exit__(self, *exc) -> bool:
        if self._client is not None and self.scheduler is None and exc[0] is None:
            self.announce("cluster stop", f"{self._name}: stopping the {self.workers} worker processes")
        self._client = None
        return self._stack.__exit__(*exc)


class QuietWorkerClose(WorkerPlugin):
    """A local cluster's worker process logs nothing once it starts closing (the campaign is done or stopped): what
    a worker closing under in-flight runs logs (its comm to the scheduler closed, its tasks cancelled) is no run's
    record and reached the terminal, with tracebacks, before the runner's one line. A run's failures are records
    (:mod:`campaigns.runner.runs`), an infrastructure failure is retried and recorded (module docstring)."""

    name = "benchtwin-quiet-close"

    def teardown(self, worker) -> None:  # called as the worker's close begins
        logging.disable(logging.CRITICAL)


def run_campaign(
    spec: CampaignSpec,
    out_dir: str | Path,
    *,
    run_function: RunModel,
    workers: int = 2,
    scheduler: str | None = None,
    resume: bool = False,
    progress: bool = True,
    allow_version_mix: bool = False,
    announce: Callable[[str, str], None] | None = None,
    cluster: Cluster | None = None,
    datasets: Collection[str] | None = None,
) -> Path:
    """Run (or resume) a campaign of ``run_function`` and write ``results.nc``; the bench twin's entry, with its
    run model by default and the fidelity audit after the runs, is :func:`campaigns.bench.campaign.run_campaign`
    (``campaigns.run_campaign``).

    Parameters
    ----------
    spec : CampaignSpec
        A validated spec.
    out_dir : str or Path
        Output directory (layout in :mod:`campaigns.runner.storage`).
    workers : int, default 2
        Worker processes of the local cluster (one thread each); ignored with ``scheduler``.
    scheduler : str, optional
        Address of an existing dask scheduler to use instead of a local cluster.
    resume : bool, default False
        Continue an interrupted campaign in ``out_dir``: finished chunks are kept,
        only missing runs execute. Refused if ``out_dir`` holds another spec's results.
    progress : bool, default True
        Show a progress bar.
    run_function : RunModel
        The model that runs (contract in :mod:`campaigns.runner.runs`).
    allow_version_mix : bool, default False
        On resume, accept finished chunks computed by other package versions or model code
        (:mod:`campaigns.runner.provenance`); ``results.nc`` then lists every provenance it mixes.
    announce : callable, optional
        ``announce(stage, message)`` is called as each stage starts (compile, cluster start, runs,
        margins, assembly, cluster stop); default silent.
    cluster : Cluster, optional
        The client to run on (started if it is not yet, left open for its owner); default: one of this campaign's
        own, of ``workers`` processes or of ``scheduler``, closed at the end. With a client already started the
        compile stage is skipped: its workers hold the compiled model.
    datasets : collection of str, optional
        Run only these data sets of the spec; ``results.nc`` then holds them alone, each with the random streams of
        its place in ``spec`` (run i of a data set has the same parameters and noise as in a campaign of the whole
        spec: the fidelity audit re-runs the data sets it needs). Default: every data set.

    Returns
    -------
    Path
        The ``results.nc`` file.

    Raises
    ------
    CampaignError
        If ``out_dir`` holds results that may not be mixed with this campaign's, is in use by
        another driver, cannot be written, or lacks the disk space the campaign needs.
        Everything is checked before the cluster starts.
    """
    announce = announce or (lambda stage, message: None)
    if not (isinstance(workers, int) and 1 <= workers <= BOUNDS["workers"][1]):
        raise CampaignError(f"workers: {workers!r} is not a whole number in [1, {BOUNDS['workers'][1]}]")
    kept = _kept_datasets(spec, datasets)
    check_disk(out_dir, estimate(spec, run_function, workers=workers))
    stores: list[ChunkStore] = []
    with _stop_signals() as stopped, contextlib.ExitStack() as own:
        if cluster is None:
            cluster = own.enter_context(Cluster(workers, scheduler, announce))
        try:
            return _run(spec, out_dir, kept=kept, resume=resume, progress=progress, run_function=run_function,
                        allow_version_mix=allow_version_mix, announce=announce, stores=stores, cluster=cluster)
        except KeyboardInterrupt:
            done = len(stores[0].done) if stores else 0
            name = stopped.name or "Ctrl-C"
            raise CampaignInterrupted(out_dir, done, len(kept) * spec.runs_per_dataset, name) from None


class _Stop:
    """Which signal stopped the campaign (``name``), set by the handlers of :func:`_stop_signals`."""

    name = ""


@contextlib.contextmanager
def _stop_signals():
    """Ctrl-C and SIGTERM stop the campaign cleanly: the first raises ``KeyboardInterrupt`` in the driver, whose
    unwinding ends the workers and the sandboxes and releases the lock; a second one while that runs ends the
    driver at once (its chunk files are complete or absent, and the OS drops the lock). Outside the main thread
    (a driver inside a server thread) nothing is installed."""
    stop = _Stop()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def first(signum, frame):
        stop.name = "Ctrl-C" if signum == signal.SIGINT else signal.Signals(signum).name
        for sig in STOP_SIGNALS:
            signal.signal(sig, again)
        raise KeyboardInterrupt

    def again(signum, frame):
        print(f"\n{signal.Signals(signum).name} again: stopping at once", file=sys.stderr, flush=True)
        os._exit(128 + signum)

    previous = {sig: signal.getsignal(sig) for sig in STOP_SIGNALS}
    for sig in STOP_SIGNALS:
        if previous[sig] is not signal.SIG_IGN:
            signal.signal(sig, first)
    try:
        yield stop
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def _compile_and_run(run_function: RunModel, request: RunRequest) -> bool:
    """Compile the run function's model once before the workers start, then run one request, both in a sandbox.

    The sandbox's start-up (imports, the run function's warm-up: numba compiles and writes its on-disk cache,
    which the workers then load) has the sandbox's own limit (:data:`campaigns.runner.sandbox.STARTUP_TIMEOUT`); the
    run has the campaign's budget (``execution.timeout`` and its grace), as every run: a spec whose runs cannot
    finish in time shows it here after that budget, not after however long the run would take. The run's time is
    not the campaign's estimate: the workers run lane groups (:func:`campaigns.runner.budget.estimate`).

    Returns whether the run ended ok within its budget.
    """
    sandbox = Sandbox()
    try:
        record = sandbox.run(run_function, request)
    finally:
        sandbox.close()
    return record["status"] == "ok"


def _kept_datasets(spec: CampaignSpec, datasets: Collection[str] | None) -> list[int]:
    """The indices of the data sets a campaign runs (:func:`run_campaign`'s ``datasets``), in spec order."""
    if datasets is None:
        return list(range(len(spec.datasets)))
    names = [d.name for d in spec.datasets]
    unknown = sorted(set(datasets) - set(names))
    if unknown or not datasets:
        raise CampaignError(f"datasets: {', '.join(unknown) or 'none given'}: name one or more of the spec's data "
                            f"sets ({', '.join(names)})")
    return [k for k, name in enumerate(names) if name in set(datasets)]


def _stored_spec(spec: CampaignSpec, kept: list[int]) -> CampaignSpec:
    """The spec the chunk store and ``results.nc`` hold: ``spec`` itself, or its ``kept`` data sets alone (their
    ``seeds_from`` dropped: each run's streams are those of its place in ``spec``, recorded per data set in
    ``results.nc``'s ``dataset_seed_indices``)."""
    if kept == list(range(len(spec.datasets))):
        return spec
    return spec.model_copy(update={"datasets": [spec.datasets[k].model_copy(update={"seeds_from": None})
                                                for k in kept]})


def _run(spec, out_dir, *, kept: list[int], resume, progress, run_function, allow_version_mix, announce,
         stores: list, cluster: Cluster) -> Path:
    """:func:`run_campaign` once its arguments are checked (``stores`` receives the chunk store, for the count of
    an interruption)."""
    stored = _stored_spec(spec, kept)
    with OutputLock(out_dir):  # held until results.nc is written
        store = ChunkStore(out_dir, stored, resume=resume, provenance=provenance(run_function),
                           allow_version_mix=allow_version_mix)
        stores.append(store)
        samples = sample(spec)  # every data set's: a kept one draws the streams of its place in the spec

        def request_of(d: int, i: int) -> RunRequest:  # d: the data set's index in the stored spec
            return dataclasses.replace(build_request(spec, samples, kept[d], i), dataset_index=d)

        pending = deque(
            (d, i) for d in range(len(kept)) for i in range(spec.runs_per_dataset) if (d, i) not in store.done
        )
        executed = len(pending)
        start = time.perf_counter()
        # once here, before the workers start, so they load the compiled code instead of compiling it; workers
        # already started hold it
        if pending and run_function.compiles and not cluster.started:
            announce("compile",
                     f"{spec.name}: compiling the model (docs/performance.md: minutes on a fresh install, seconds "
                     f"once cached), then one run within its {spec.execution.timeout:g} s budget")
            if not _compile_and_run(run_function, request_of(*pending[0])):
                announce("compile", f"{spec.name}: the run did not end ok within its budget")
        client = None
        if pending:
            client = cluster.client(spec.name)
            cost = estimate(stored, run_function, workers=cluster.slots, runs=len(pending))
            announce("runs", f"{spec.name}: {cost.runs} runs ({cost.duration()})")
            with tqdm(total=len(pending), disable=not progress, unit="run", desc=spec.name) as bar:
                _execute(client, stored, request_of, pending, run_function, store, bar)
        elif cluster.started:
            client = cluster.client(spec.name)
        attrs = {"run_function": run_function_name(run_function), **run_function.results_attributes(stored)}
        if stored is not spec:
            attrs["dataset_seed_indices"] = json.dumps({spec.datasets[k].name: spec.seed_index(k) for k in kept})
        announce("margins", f"{spec.name}: the model's per-run variables (the bench: loop margins) of "
                 f"{len(kept) * spec.runs_per_dataset} runs" + (" on the cluster" if client else ""))
        on_cluster = (lambda f, chunks: client.gather(client.map(f, chunks, pure=False))) if client else None
        margins = run_function.margin_variables(stored, request_of, on_cluster)
        announce("assembly", f"{spec.name}: writing results.nc")
        return store.assemble(samples[kept],
                              {"executed_runs": executed, "execution_wall_time": time.perf_counter() - start,
                               "workers": cluster.scheduler or cluster.workers}, attrs, margins)


def _execute(client: Client, spec, request_of, pending: deque, run_function, store: ChunkStore, bar) -> None:
    slots = max(1, sum(client.nthreads().values()))
    run_times: list[float] = []
    in_flight: dict = {}
    completed = as_completed()

    def submit(chunk: list[RunRequest], attempt: int) -> None:
        future = client.submit(run_chunk, run_function, chunk, spec.execution.isolation, pure=False)
        in_flight[future] = (chunk, attempt)
        completed.add(future)

    lanes = run_function.lanes

    def next_chunk() -> list[RunRequest]:
        size = spec.execution.chunk_size or chunk_size(
            statistics.median(run_times) if run_times else None, len(pending), slots
        )
        size = lanes * math.ceil(size / lanes)  # whole lane groups (the pilot: one group)
        d = pending[0][0]
        chunk = []
        while pending and len(chunk) < size and pending[0][0] == d:
            chunk.append(request_of(*pending.popleft()))
        return chunk

    def refill() -> None:
        while pending and len(in_flight) < 2 * slots:
            submit(next_chunk(), 0)

    refill()
    for future in completed:
        chunk, attempt = in_flight.pop(future)
        try:
            records = future.result()
        except INFRASTRUCTURE_ERRORS as exc:
            if attempt < MAX_RETRIES:
                submit(chunk, attempt + 1)
                continue
            reason = f"infrastructure failure after {MAX_RETRIES} retries: {type(exc).__name__}: {exc}"
            records = [record(r, "lost", reason, math.nan, math.nan) for r in chunk]
        store.write_chunk(records)
        run_times.extend(r["wall_time"] for r in records if r["status"] == "ok")
        bar.update(len(records))
        refill()
