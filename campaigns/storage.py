"""Chunk files while a campaign runs, and the final ``results.nc``.

Layout of an output directory::

    OUT/
      spec.json                   canonical spec + its hash (written first)
      chunks/<hash[:16]>/         one file per finished chunk
        d003-r000120-000159.npz   runs 120..159 of data set 3
      results.nc                  assembled when every run has a record

Every file is written to a temporary name in the same directory and moved into
place with :func:`os.replace`, so a killed driver leaves either a complete file
or a stray ``*.tmp`` (removed on resume), never a truncated chunk. Only the
driver writes (workers may not share a file system with it), and each chunk is
its own file because concurrent writes to one netCDF/HDF5 file are unsafe.
"""

from __future__ import annotations

import json
import math
import os
import platform
import tempfile
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

import numpy as np
import xarray as xr

from campaigns.catalog import CONDITION_UNITS
from campaigns.runs import STATUS_MEANINGS
from campaigns.spec import HALF_RANGE_SIGMAS, CampaignSpec

RESULTS_NAME = "results.nc"
_VERSIONED = ("benchtwin", "numpy", "scipy", "xarray", "netCDF4", "dask", "distributed", "pydantic", "numba")


class CampaignError(RuntimeError):
    """The campaign cannot proceed (e.g. an output directory holding another spec's results)."""


def atomic_write(path: Path, write) -> None:
    """Call ``write(tmp_path)`` then move the file onto ``path`` atomically."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        write(Path(tmp))
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


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

    def __init__(self, out_dir: str | Path, spec: CampaignSpec, *, resume: bool = False):
        self.root = Path(out_dir)
        self.spec = spec
        self.hash = spec.spec_hash()
        manifest = self.root / "spec.json"
        if manifest.exists():
            if not resume:
                raise CampaignError(
                    f"{self.root} already holds campaign results; pass resume=True (--resume) to continue them or choose another output directory"
                )
            stored = json.loads(manifest.read_text())
            if stored["hash"] != self.hash:
                differ = _differences(stored["canonical"], spec.canonical())
                raise CampaignError(
                    f"{self.root} holds results of a different spec (hash {stored['hash'][:16]}, this spec {self.hash[:16]}; "
                    f"differences in: {', '.join(differ)}); refusing to mix them. Use another output directory."
                )
        self.chunk_dir = self.root / "chunks" / self.hash[:16]
        self.chunk_dir.mkdir(parents=True, exist_ok=True)
        if not manifest.exists():
            text = json.dumps({"hash": self.hash, "canonical": spec.canonical()}, indent=1, sort_keys=True)
            atomic_write(manifest, lambda p: p.write_text(text))
        for stray in self.chunk_dir.glob(".*.tmp"):
            stray.unlink()
        self.done = {(int(z["dataset_index"]), int(r)) for z in map(_load, self.chunk_files()) for r in z["run"]}

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
        path = self.chunk_dir / f"d{d:03d}-r{runs.min():06d}-{runs.max():06d}.npz"

        def write(tmp: Path) -> None:
            with open(tmp, "wb") as f:
                np.savez(f, **arrays)

        atomic_write(path, write)
        self.done.update((d, int(r)) for r in runs)
        return path

    def assemble(self, samples: np.ndarray, execution: dict | None = None, attrs: dict | None = None) -> Path:
        """Write ``results.nc`` from the chunk files and the samples; return its path.

        ``execution`` (runs executed by this invocation, its wall time [s], the workers or scheduler)
        is recorded in the attributes as ``execution_*``: a resumed campaign reports its last leg.
        ``attrs`` are further attributes as they are (e.g. the driver's ``dataset_conditions``).
        """
        ds = build_results(self.spec, samples, [_load(p) for p in self.chunk_files()])
        for key, value in (execution or {}).items():
            ds.attrs[key if key.startswith("execution") else f"execution_{key}"] = value
        ds.attrs.update(attrs or {})
        path = self.root / RESULTS_NAME
        atomic_write(path, lambda p: ds.to_netcdf(p, engine="netcdf4"))
        return path


def _load(path: Path) -> dict:
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


def _padded(trace: xr.Dataset, variable: str, length: int) -> np.ndarray:
    out = np.full(length, math.nan)
    if variable in trace:
        values = np.asarray(trace[variable].values, dtype=float)
        out[: len(values)] = values
    return out


def _units(trace: xr.Dataset, variable: str) -> str:
    return str(trace[variable].attrs.get("units", "")) if variable in trace else ""


def _differences(a: dict, b: dict) -> list[str]:
    sa, sb = a["spec"], b["spec"]
    keys = sorted(k for k in set(sa) | set(sb) if sa.get(k) != sb.get(k))
    return keys or ["resolved distributions (nominal values of the parameter set)"]


def package_versions() -> dict[str, str]:
    """Versions of the packages that determine the results."""
    versions = {"python": platform.python_version()}
    for name in _VERSIONED:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


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
        attrs = {"units": dist.unit, "long_name": long_name, "role": "sampled", "distribution": json.dumps(dist.as_dict())}
        data_vars[dist.target] = (dims, samples[:, :, k], attrs)
    for f in spec.features:
        unit, long_name = spec.feature_meta(f)
        data_vars[f] = (dims, features[f], {"units": unit, "long_name": long_name, "role": "feature"})
    data_vars["status"] = (dims, status, {"long_name": "run status", "flag_meanings": json.dumps(STATUS_MEANINGS)})
    data_vars["failure_reason"] = (dims, reason, {"long_name": "why the run failed (empty when ok)"})
    data_vars["t_reached"] = (dims, t_reached, {"units": "s", "long_name": "simulated time reached"})
    data_vars["wall_time"] = (dims, wall_time, {"units": "s", "long_name": "wall-clock time of the run (machine dependent)"})
    for key, unit in CONDITION_UNITS.items():
        values = [ds.conditions.get(key, math.nan) for ds in spec.datasets]
        if any(not math.isnan(v) for v in values):
            long_name = f"data-set condition {key} (NaN: the scene's own value)"
            data_vars[f"condition_{key}"] = (("dataset",), np.array(values, dtype=float), {"units": unit, "long_name": long_name})
    coords = {
        "dataset": ("dataset", np.array([d.name for d in spec.datasets], dtype=object), {"long_name": "data set"}),
        "run": ("run", np.arange(spec.runs_per_dataset, dtype=np.int64), {"long_name": "run index within the data set"}),
        "scene": ("dataset", np.array([d.scene or spec.base.scene for d in spec.datasets], dtype=object), {"long_name": "scene"}),
    }
    if k_traces and trace_len:
        coords["trace_run"] = ("trace_run", np.arange(k_traces, dtype=np.int64), {"long_name": "run index of the kept traces"})
        coords["trace_time"] = ("trace_time", trace_time, {"units": "s", "long_name": "time", "standard_name": "time"})
        for v in spec.traces.variables:
            attrs = {"units": trace_units[v], "long_name": f"{v}, decimated by {spec.traces.decimation}"}
            data_vars[f"trace_{v}"] = (("dataset", "trace_run", "trace_time"), traces[v], attrs)
    attrs = {
        "Conventions": "CF-1.8",
        "title": f"BenchTwin Monte Carlo campaign {spec.name}",
        "source": "BenchTwin campaign runner (campaigns package)",
        "campaign": spec.name,
        "spec_json": spec.to_json(),
        "spec_hash": spec.spec_hash(),
        "root_seed_entropy": str(spec.root_seed),
        "seeding": "run i of data set d: SeedSequence(root_seed, spawn_key=(d, i)).spawn(2) -> [parameters, sensor noise]",
        "half_range_sigmas": HALF_RANGE_SIGMAS,
        "package_versions": json.dumps(package_versions(), sort_keys=True),
        "date_created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "fidelity_requested": json.dumps(spec.solver.fidelity),
        **{f"fidelity_{d.name}": " | ".join(sorted(used)) for d, used in zip(spec.datasets, fidelity) if used},
    }
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)
