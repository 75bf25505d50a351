"""Chunk files while a campaign runs, and the final ``results.nc``.

Layout of an output directory::

    OUT/
      .lock                       held (flock) by the driver that owns OUT while it runs
      spec.json                   canonical spec + its hash (written first)
      chunks/<hash[:16]>/         one file per finished chunk
        d003-r000120-000159.npz   runs 120..159 of data set 3
      corrupt/                    chunk files found damaged on resume (moved aside, their runs re-run)
      results.nc                  assembled when every run has a record

One driver owns a directory: :class:`OutputLock` takes an exclusive ``fcntl.flock`` on
``OUT/.lock`` for the driver's lifetime (the OS releases it when the driver dies, even by
SIGKILL), and a second driver is refused at once. Every file is written to a temporary name
in the same directory and moved into place with :func:`os.replace`, so a killed driver
leaves either a complete file or a stray ``.*.tmp``; a new owner removes those strays
(they can only be a dead driver's, since a live one would hold the lock). Only the driver
writes (workers may not share a file system with it), and each chunk is its own file
because concurrent writes to one netCDF/HDF5 file are unsafe.

Integrity: a chunk carries a SHA-256 of its arrays (``checksum``) on top of the zip
CRC-32 of each array; both are verified whenever the chunk is read. On resume a chunk
that fails (truncated, corrupt, incomplete) is named, moved to ``OUT/corrupt/`` and its
runs run again. Each chunk records the provenance of the code that computed it
(:mod:`campaigns.runner.provenance`); a resume refuses to mix provenances unless told to.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import logging
import math
import os
import socket
import time
import zipfile
import zlib
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import xarray as xr

from campaigns.runner import provenance as prov
from campaigns.runner.files import CONVENTIONS, CampaignError, atomic_write, check_output, write_netcdf
from campaigns.runner.provenance import package_versions
from campaigns.runner.runs import STATUS_MEANINGS, STATUSES
from campaigns.runner.sampling import UNIT_STREAM
from campaigns.runner.spec import CampaignSpec
from campaigns.units import HALF_RANGE_SIGMAS

RESULTS_NAME = "results.nc"
LOCK_NAME = ".lock"
CORRUPT_DIR = "corrupt"
#: Arrays every chunk holds (besides ``feature/<name>`` per feature).
CHUNK_KEYS = ("dataset_index", "run", "status", "failure_reason", "t_reached", "wall_time")

_log = logging.getLogger("campaigns")

__all__ = ["CampaignError", "ChunkStore", "OutputLock", "atomic_write", "build_results", "check_output",
           "package_versions", "read_results", "write_netcdf"]


class CorruptChunk(CampaignError):
    """A chunk file cannot be read back intact."""


class OutputLock:
    """Exclusive ownership of an output directory for as long as the lock is held.

    ``fcntl.flock`` on ``OUT/.lock``; the file holds the owner's pid, host and start time
    for the refusal message. The OS drops the lock when the owner exits or dies. A clean
    release (the end of a campaign, Ctrl-C, SIGTERM) also removes the file, so nothing stale
    is left; an owner checks, once it holds the lock, that the file it locked is still the one
    in the directory (a release may have removed it in between), and locks the new one otherwise.
    (flock is reliable on local file systems; on NFS use one driver per directory by hand.)
    """

    def __init__(self, out_dir: str | Path):
        self.root = Path(out_dir)
        self.path = self.root / LOCK_NAME
        self._fd: int | None = None

    def acquire(self) -> OutputLock:
        while True:
            try:
                self.root.mkdir(parents=True, exist_ok=True)
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            except OSError as exc:
                raise CampaignError(f"cannot use output directory {self.root}: {exc.strerror or exc}") from exc
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.pread(fd, 4096, 0).decode(errors="replace").strip() or "unknown process"
                os.close(fd)
                raise CampaignError(f"{self.root} is in use by another campaign driver ({holder}); "
                                    "wait for it to finish, or choose another output directory") from None
            try:
                current = os.stat(self.path).st_ino
            except FileNotFoundError:
                current = None
            if current == os.fstat(fd).st_ino:
                break
            os.close(fd)  # locked a file a releasing owner had just removed: lock the directory's own
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()} on {socket.gethostname()}, since "
                      f"{datetime.now(UTC).isoformat(timespec='seconds')}\n".encode(), 0)
        self._fd = fd
        return self

    def release(self) -> None:
        if self._fd is not None:
            try:
                self.path.unlink(missing_ok=True)  # still locked: nobody else can be using it
            except OSError:
                os.ftruncate(self._fd, 0)  # a read-only directory: at least no stale owner in it
            fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> OutputLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()


class ChunkStore:
    """The chunk files of one campaign in ``out_dir``.

    Parameters
    ----------
    out_dir : str or Path
        Output directory (created if needed).
    spec : CampaignSpec
    resume : bool
        Continue an interrupted campaign. Without it, a directory that already
        holds campaign results is refused; with it, a directory holding results
        of a *different* spec is refused.

    Attributes
    ----------
    done : set of (int, int)
        ``(dataset_index, run_index)`` of every run already recorded.
    """

    def __init__(self, out_dir: str | Path, spec: CampaignSpec, *, resume: bool = False,
                 provenance: dict[str, str] | None = None, allow_version_mix: bool = False):
        self.root = Path(out_dir)
        self.spec = spec
        self.hash = spec.spec_hash()
        self.provenance = provenance or {}
        self.quarantined: list[Path] = []
        manifest = self.root / "spec.json"
        self._refuse_foreign_results(manifest, resume)
        if manifest.exists() and self._holds_results():
            stored = _read_manifest(manifest)
            if stored["hash"] != self.hash:
                differ = _differences(stored["canonical"], spec.canonical())
                raise CampaignError(
                    f"{self.root} holds results of a different spec (hash {stored['hash'][:16]}, "
                    f"this spec {self.hash[:16]}; differences in: {', '.join(differ)}); refusing to mix them. "
                    + _resume_hint(stored["canonical"], spec.canonical(), self.root)
                )
        self.chunk_dir = self.root / "chunks" / self.hash[:16]
        try:
            self.chunk_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise CampaignError(f"cannot create {self.chunk_dir}: {exc.strerror or exc}") from exc
        if not manifest.exists() or not self._holds_results():
            text = json.dumps({"hash": self.hash, "canonical": spec.canonical()}, indent=1, sort_keys=True)
            atomic_write(manifest, lambda p: p.write_text(text))
        for directory in (self.root, self.chunk_dir):  # a dead owner's temporaries (see the module docstring)
            for stray in directory.glob(".*.tmp"):
                stray.unlink()
        chunks = self._intact_chunks()
        self._check_provenance(chunks, allow_version_mix)
        self.done = {(int(z["dataset_index"]), int(r)) for z in chunks for r in z["run"]}

    def _holds_results(self) -> bool:
        """Whether the directory holds any campaign output (results.nc or a chunk file)."""
        return (self.root / RESULTS_NAME).exists() or any((self.root / "chunks").glob("*/*.npz"))

    def _refuse_foreign_results(self, manifest: Path, resume: bool) -> None:
        if not self._holds_results():
            return  # empty, or a spec.json left by a driver killed before its first chunk: nothing to lose
        if not manifest.exists():
            raise CampaignError(
                f"{self.root} holds campaign results ({RESULTS_NAME} or chunks/) but no spec.json, so nothing tells "
                "which spec made them; refusing to touch them. Choose another output directory."
            )
        if not resume:
            raise CampaignError(
                f"{self.root} already holds campaign results; pass resume=True "
                "(--resume) to continue them or choose another output directory"
            )

    def _intact_chunks(self) -> list[dict]:
        """Load every chunk; move the damaged ones to ``OUT/corrupt/`` (their runs will run again)."""
        chunks = []
        for path in self.chunk_files():
            try:
                chunks.append(load_chunk(path, self.spec.features))
            except CorruptChunk as exc:
                target = self.root / CORRUPT_DIR / self.hash[:16] / f"{path.name}.{time.strftime('%Y%m%dT%H%M%S')}"
                target.parent.mkdir(parents=True, exist_ok=True)
                os.replace(path, target)
                self.quarantined.append(target)
                _log.warning("%s; moved to %s, its runs will run again", exc, target)
        return chunks

    def _check_provenance(self, chunks: list[dict], allow_version_mix: bool) -> None:
        stored = {str(c.get("provenance", "")) for c in chunks}
        mine = prov.as_text(self.provenance)
        foreign = sorted(stored - {mine})
        if not foreign or allow_version_mix:
            return
        why = []
        for text in foreign:
            old = json.loads(text) if text else {}
            why += prov.differences(old, self.provenance) if old else ["chunks written without a recorded provenance"]
        raise CampaignError(
            f"{self.root}: the finished chunks were computed by another version ({'; '.join(sorted(set(why)))}); "
            "resuming would mix numbers of two versions in one results.nc. Re-run into a new directory, or pass "
            "allow_version_mix=True (--allow-version-mix) to accept the mix (results.nc then lists every version)."
        )

    def chunk_files(self) -> list[Path]:
        """Finished chunk files, sorted by name."""
        return sorted(self.chunk_dir.glob("d*.npz"))

    def write_chunk(self, records: list[dict]) -> Path:
        """Write the records of one chunk (all from one data set) atomically."""
        d = records[0]["dataset_index"]
        runs = np.array([r["run_index"] for r in records], dtype=np.int64)
        arrays = {
            "dataset_index": np.int64(d),
            "run": runs,
            "status": np.array([r["status"] for r in records], dtype=str),
            "failure_reason": np.array([r["failure_reason"] for r in records], dtype=str),
            "t_reached": np.array([r["t_reached"] for r in records]),
            "wall_time": np.array([r["wall_time"] for r in records]),
            "fidelity": np.array([r.get("fidelity", "") for r in records], dtype=str),
            "integrator": np.array([r.get("integrator", "") for r in records], dtype=str),
            "provenance": np.array(prov.as_text(self.provenance)),
        }
        for f in self.spec.features:
            arrays[f"feature/{f}"] = np.array([r["features"][f] for r in records])
        traced = [r for r in records if r["trace"] is not None]
        if traced:
            arrays["trace_run"] = np.array([r["run_index"] for r in traced], dtype=np.int64)
            time = max((r["trace"]["time"].values for r in traced), key=len)
            arrays["trace_time"] = time
            for v in self.spec.traces.variables:
                arrays[f"trace/{v}"] = np.stack([_padded(r["trace"], v, len(time)) for r in traced])
                arrays[f"trace_units/{v}"] = np.array(_units(traced[0]["trace"], v))
        arrays["checksum"] = np.array(_checksum(arrays))
        path = self.chunk_dir / f"d{d:03d}-r{runs.min():06d}-{runs.max():06d}.npz"

        def write(tmp: Path) -> None:
            with open(tmp, "wb") as f:
                np.savez(f, **arrays)

        atomic_write(path, write)
        self.done.update((d, int(r)) for r in runs)
        return path

    def assemble(self, samples: np.ndarray, execution: dict | None = None, attrs: dict | None = None,
                 variables: dict | None = None) -> Path:
        """Write ``results.nc`` from the chunk files and the samples; return its path.

        ``execution`` (runs executed by this invocation, its wall time [s], the workers or scheduler)
        is recorded in the attributes as ``execution_*``: a resumed campaign reports its last leg.
        ``attrs`` are further global attributes as they are (e.g. the run function, the driver's
        ``dataset_conditions``). ``variables`` are further ``(dims, values, attrs)`` variables (the bench's
        per-run loop margins, :func:`campaigns.bench.adapter.margin_variables`).
        """
        ds = build_results(self.spec, samples, [load_chunk(p, self.spec.features) for p in self.chunk_files()])
        ds = ds.assign(variables or {})
        for key, value in (execution or {}).items():
            ds.attrs[key if key.startswith("execution") else f"execution_{key}"] = value
        ds.attrs.update(attrs or {})
        path = self.root / RESULTS_NAME
        runs = ds.sizes["dataset"] * ds.sizes["run"]
        return write_netcdf(ds, path, title=ds.attrs["title"],
                            history=f"{runs} runs of campaign {self.spec.name} assembled from "
                                    f"{len(self.chunk_files())} chunk files by BenchTwin (campaigns.runner.storage)")


#: What a campaign's results.nc holds at least (besides the ``spec_json`` attribute).
RESULTS_VARIABLES = ("status",)


def read_results(path: str | Path) -> xr.Dataset:
    """A campaign's ``results.nc``, loaded and checked: every problem is one :class:`CampaignError` naming the file.

    Raises
    ------
    CampaignError
        If the file is missing, a directory, unreadable (truncated, not netCDF) or not a campaign's results.
    """
    path = Path(path)
    if not path.exists():
        raise CampaignError(f"{path}: no such file; give the results.nc that `twin campaign run` wrote")
    if path.is_dir():
        hint = f" ({path / RESULTS_NAME})" if (path / RESULTS_NAME).is_file() else ""
        raise CampaignError(f"{path} is a directory; give the campaign's results.nc{hint}")
    ds = _load_netcdf(path, "A results.nc cut short is rebuilt from its chunk files by "
                            "`twin campaign run SPEC --out DIR --resume`")
    problems = [] if "spec_json" in ds.attrs else ["no spec_json attribute"]
    problems += [f"no {v!r} variable" for v in RESULTS_VARIABLES if v not in ds.variables]
    problems += [f"no {d!r} dimension" for d in ("dataset", "run") if d not in ds.dims]
    if problems:
        raise CampaignError(f"{path} is not a campaign's results.nc ({'; '.join(problems)}); give the results.nc "
                            "that `twin campaign run` wrote")
    return ds


def read_analysis(path: str | Path, results_path: str | Path) -> xr.Dataset:
    """The ``analysis.nc`` of the campaign whose results are ``results_path``, loaded.

    Raises
    ------
    CampaignError
        If it cannot be read (truncated, not netCDF): naming the file and the command that writes it again.
    """
    return _load_netcdf(Path(path), f"`twin campaign analyze {results_path} --force` writes it again")


def _load_netcdf(path: Path, remedy: str) -> xr.Dataset:
    try:
        with xr.open_dataset(path, engine="netcdf4") as handle:
            return handle.load()
    except Exception as exc:  # noqa: BLE001 - netCDF4/HDF5 raise OSError, RuntimeError, ValueError... for a bad file
        first = str(exc).splitlines()[0] if str(exc) else ""
        raise CampaignError(f"{path}: cannot be read as a netCDF file ({type(exc).__name__}: {first}); is it "
                            f"complete? {remedy}") from None


def _checksum(arrays: dict) -> str:
    """SHA-256 over every array of a chunk (name, dtype, shape, bytes), ``checksum`` itself excluded."""
    digest = hashlib.sha256()
    for key in sorted(k for k in arrays if k != "checksum"):
        value = np.ascontiguousarray(arrays[key])
        digest.update(f"{key}\0{value.dtype.str}\0{value.shape}\0".encode())
        digest.update(value.tobytes())
    return digest.hexdigest()


def load_chunk(path: Path, features=()) -> dict:
    """Read a chunk file and verify it (zip CRC-32, checksum, required arrays, consistent lengths).

    Raises
    ------
    CorruptChunk
        Naming the file and what is wrong with it.
    """
    try:
        with open(path, "rb") as f, np.load(f, allow_pickle=False) as z:  # our handle: closed even if np.load fails
            chunk = {k: z[k] for k in z.files}
    except (zipfile.BadZipFile, EOFError, ValueError, OSError, KeyError, zlib.error) as exc:
        raise CorruptChunk(f"corrupt chunk {path} ({type(exc).__name__}: {exc})") from exc
    missing = [k for k in (*CHUNK_KEYS, *(f"feature/{f}" for f in features)) if k not in chunk]
    if missing:
        raise CorruptChunk(f"corrupt chunk {path} (missing {', '.join(missing)})")
    n = len(chunk["run"])
    uneven = [k for k in chunk if k in CHUNK_KEYS[2:] or k.startswith("feature/") if len(chunk[k]) != n]
    if uneven:
        raise CorruptChunk(f"corrupt chunk {path} ({', '.join(uneven)} not of {n} runs)")
    if "checksum" in chunk and str(chunk["checksum"]) != _checksum(chunk):
        raise CorruptChunk(f"corrupt chunk {path} (checksum mismatch)")
    return chunk


def _read_manifest(path: Path) -> dict:
    try:
        stored = json.loads(path.read_text(encoding="utf-8"))
        stored["hash"], stored["canonical"]  # noqa: B018 - both must exist
        return stored
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise CampaignError(f"{path} is unreadable ({type(exc).__name__}: {exc}); cannot tell which spec made the "
                            "results beside it. Choose another output directory.") from exc


def _padded(trace: xr.Dataset, variable: str, length: int) -> np.ndarray:
    out = np.full(length, math.nan)
    if variable in trace:
        values = np.asarray(trace[variable].values, dtype=float)
        out[: len(values)] = values
    return out


def _units(trace: xr.Dataset, variable: str) -> str:
    return str(trace[variable].attrs.get("units", "")) if variable in trace else ""


def _differences(a: dict, b: dict) -> list[str]:
    """The spec fields that differ, with the stored and the new value where they are short."""
    sa, sb = a["spec"], b["spec"]
    keys = sorted(k for k in set(sa) | set(sb) if sa.get(k) != sb.get(k))
    out = []
    for key in keys:
        old, new = sa.get(key), sb.get(key)
        if isinstance(old, dict) and isinstance(new, dict):
            out += [f"{key}.{k} (stored {old.get(k)!r}, now {new.get(k)!r})" for k in sorted(set(old) | set(new))
                    if old.get(k) != new.get(k)]
        elif len(repr(old)) + len(repr(new)) < 80:
            out.append(f"{key} (stored {old!r}, now {new!r})")
        else:
            out.append(key)
    return out or ["resolved distributions (nominal values of the parameter set)"]


#: Spec fields a command-line option overrides: what to repeat to resume results made with it.
_OPTIONS = {("runs_per_dataset",): "--runs", ("execution", "timeout"): "--timeout"}


def _resume_hint(stored: dict, mine: dict, root: Path) -> str:
    """What would make this run match the stored results: the options they were made with, when the spec file
    is the same and only overridden fields differ; else another output directory."""
    sa, sb = stored["spec"], mine["spec"]
    overridable = {path[0] for path in _OPTIONS}
    rest_a = {k: v for k, v in sa.items() if k not in overridable}
    rest_b = {k: v for k, v in sb.items() if k not in overridable}
    execution_a, execution_b = dict(sa.get("execution") or {}), dict(sb.get("execution") or {})
    execution_a.pop("timeout", None), execution_b.pop("timeout", None)
    options = []
    for path, option in _OPTIONS.items():
        old, new = sa, sb
        for key in path:
            old, new = (old or {}).get(key), (new or {}).get(key)
        if old != new:
            options.append(f"{option} {old:g}" if isinstance(old, float) else f"{option} {old}")
    if rest_a == rest_b and execution_a == execution_b and stored.get("resolved") == mine.get("resolved") and options:
        return (f"They were made with {' '.join(options)}: to resume them, repeat it (e.g. `twin campaign run SPEC "
                f"--out {root} --resume {' '.join(options)}`); or use another output directory.")
    return "Resume with the spec and options that made them, or use another output directory."


def _provenance_attrs(chunks: list[dict]) -> dict[str, str]:
    """``benchtwin_version``, ``model_code_hash``, ``provenance`` (every distinct one) and ``version_mix``."""
    texts = sorted({str(c.get("provenance", "")) for c in chunks})
    records = [json.loads(t) if t else {} for t in texts]
    first = records[0] if records else {}
    mixed = len(records) > 1
    return {
        "benchtwin_version": first.get("benchtwin", "unknown") if not mixed else "mixed: " + ", ".join(
            sorted({r.get("benchtwin", "unknown") for r in records})),
        "model_code_hash": first.get("model_code", "unknown") if not mixed else "mixed",
        "model_code_packages": first.get("model_packages", ""),
        "provenance": json.dumps(records, sort_keys=True),
        "version_mix": ("MIXED (allowed by --allow-version-mix): " + " | ".join(
            "; ".join(prov.differences(records[0], r)) for r in records[1:])) if mixed else "none",
    }


def build_results(spec: CampaignSpec, samples: np.ndarray, chunks: list[dict]) -> xr.Dataset:
    """Assemble the results dataset (schema in ``docs/campaigns.md``).

    Raises
    ------
    CampaignError
        If a run has no record.
    """
    shape = (len(spec.datasets), spec.runs_per_dataset)
    filled = np.zeros(shape, dtype=bool)
    status = np.full(shape, "", dtype=object)
    reason = np.full(shape, "", dtype=object)
    integrator = np.full(shape, "", dtype=object)
    t_reached, wall_time = np.full(shape, math.nan), np.full(shape, math.nan)
    features = {f: np.full(shape, math.nan) for f in spec.features}
    k_traces = min(spec.traces.runs_per_dataset, spec.runs_per_dataset)
    trace_len = max((len(c["trace_time"]) for c in chunks if "trace_time" in c), default=0)
    trace_time = np.full(trace_len, math.nan)
    trace_units = {v: "" for v in spec.traces.variables}
    traces = {v: np.full((shape[0], k_traces, trace_len), math.nan) for v in spec.traces.variables}
    fidelity: list[set[str]] = [set() for _ in spec.datasets]
    for c in chunks:
        d, runs = int(c["dataset_index"]), c["run"]
        filled[d, runs] = True
        status[d, runs] = c["status"].astype(object)
        reason[d, runs] = c["failure_reason"].astype(object)
        if "integrator" in c:  # chunks written before the automatic integrator have none
            integrator[d, runs] = c["integrator"].astype(object)
        t_reached[d, runs], wall_time[d, runs] = c["t_reached"], c["wall_time"]
        fidelity[d].update(str(f) for f in c.get("fidelity", ()) if str(f))
        for f in spec.features:
            features[f][d, runs] = c[f"feature/{f}"]
        if "trace_run" in c:
            n = len(c["trace_time"])
            if n == trace_len:
                trace_time[:] = c["trace_time"]
            for v in spec.traces.variables:
                traces[v][d, c["trace_run"], :n] = c[f"trace/{v}"]
                trace_units[v] = trace_units[v] or str(c[f"trace_units/{v}"])
    if not filled.all():
        missing = int((~filled).sum())
        raise CampaignError(f"{missing} run(s) have no record; resume the campaign to finish them")

    dims = ("dataset", "run")
    data_vars = {}
    for k, dist in enumerate(spec.distributions()):
        long_name = dist.target + (f" ({dist.source})" if dist.source else "")
        attrs = {"units": dist.unit, "long_name": long_name, "role": "sampled",
                 "distribution": json.dumps(dist.as_dict())}
        data_vars[dist.target] = (dims, samples[:, :, k], attrs)
    for f in spec.features:
        unit, long_name = spec.feature_meta(f)
        data_vars[f] = (dims, features[f], {"units": unit, "long_name": long_name, "role": "feature"})
    data_vars["status"] = (dims, status, {
        "long_name": "run status: " + ", ".join(STATUSES) + " (coded in status_flag)",
        "comment": "\n".join(f"{k}: {v}" for k, v in STATUS_MEANINGS.items())})
    data_vars["status_flag"] = (dims, np.vectorize(STATUSES.index, otypes=[np.int8])(status), {
        "long_name": "run status as a CF flag (status as a number)",
        "flag_values": np.arange(len(STATUSES), dtype=np.int8), "flag_meanings": " ".join(STATUSES)})
    data_vars["failure_reason"] = (dims, reason, {"long_name": "why the run failed (empty when ok)"})
    data_vars["integrator"] = (dims, integrator, {
        "long_name": "method and step that solved the run, e.g. 'rk4 at 62.5 us' (a method alone: written before "
                     "the step was recorded; empty: not recorded)"})
    data_vars["t_reached"] = (dims, t_reached, {"units": "s", "long_name": "simulated time reached"})
    data_vars["wall_time"] = (dims, wall_time,
                              {"units": "s", "long_name": "wall-clock time of the run (machine dependent)"})
    for key, unit in spec.condition_units().items():
        values = [ds.conditions.get(key, math.nan) for ds in spec.datasets]
        if any(not math.isnan(v) for v in values):
            long_name = f"data-set condition {key} (NaN: the scene's own value)"
            data_vars[f"condition_{key}"] = (("dataset",), np.array(values, dtype=float),
                                             {"units": unit, "long_name": long_name})
    coords = {
        "dataset": ("dataset", np.array([d.name for d in spec.datasets], dtype=object), {"long_name": "data set"}),
        "run": ("run", np.arange(spec.runs_per_dataset, dtype=np.int32),
                {"units": "1", "long_name": "run index within the data set"}),
        "scene": ("dataset", np.array([d.scene or spec.base.scene for d in spec.datasets], dtype=object),
                  {"long_name": "scene"}),
    }
    if spec.units is not None:  # a within-unit campaign: run i of every data set is test i % R of unit i // R
        runs = np.arange(spec.runs_per_dataset, dtype=np.int32)
        coords["unit"] = ("run", runs // spec.units.repeats, {
            "units": "1", "long_name": "unit the run tests (its fixed errors drawn once per unit, shared by all its "
                                       "tests in every data set)"})
        coords["repeat"] = ("run", runs % spec.units.repeats, {
            "units": "1", "long_name": "test of the unit at the data set's fault level (its per-test uncertainties "
                                       "and noise redrawn)"})
    if k_traces and trace_len:
        coords["trace_run"] = ("trace_run", np.arange(k_traces, dtype=np.int32),
                               {"units": "1", "long_name": "run index of the kept traces"})
        # elapsed time of a simulated test procedure, not a calendar instant: no CF "time" (which needs an epoch)
        coords["trace_time"] = ("trace_time", trace_time,
                                {"units": "s", "long_name": "time since the start of the test procedure"})
        for v in spec.traces.variables:
            attrs = {"units": trace_units[v], "long_name": f"{v}, decimated by {spec.traces.decimation}"}
            data_vars[f"trace_{v}"] = (("dataset", "trace_run", "trace_time"), traces[v], attrs)
    attrs = {
        "Conventions": CONVENTIONS,
        "title": f"BenchTwin Monte Carlo campaign {spec.name}",
        "source": "BenchTwin campaign runner (campaigns package)",
        "campaign": spec.name,
        "spec_json": spec.to_json(),
        "spec_hash": spec.spec_hash(),
        "root_seed_entropy": str(spec.root_seed),
        "seeding": "run i of data set d: SeedSequence(root_seed, spawn_key=(d, i)).spawn(2) -> [parameters, "
                   "sensor noise]; d is the index of the data set named by seeds_from where a data set sets it"
                   + (f"; [units]: run i tests unit u = i // {spec.units.repeats}, whose rows other than "
                      f"{', '.join(spec.per_test_targets()) or 'none'} are drawn from SeedSequence(root_seed, "
                      f"spawn_key=({UNIT_STREAM}, u)), the same in every data set" if spec.units is not None else ""),
        "half_range_sigmas": HALF_RANGE_SIGMAS,
        "package_versions": json.dumps(package_versions(), sort_keys=True),
        **_provenance_attrs(chunks),
        "date_created": datetime.now(UTC).isoformat(timespec="seconds"),
        "fidelity_requested": json.dumps(spec.solver.fidelity),
        **{f"fidelity_{d.name}": " | ".join(sorted(used)) for d, used in zip(spec.datasets, fidelity, strict=False)
           if used},
    }
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)
