"""Writing campaign files safely: the one rule for every command that writes, the atomic write, the netCDF writer.

A module of its own, below the storage layout (:mod:`campaigns.runner.storage`), so that the analysis and
the audits can write their files without importing the spec, the bench adapter and the twin.

The rule (:func:`check_output`), used by every command that writes a file (``twin simulate --out/--plot``,
``twin campaign analyze/replay --out``, ``twin report``, ``twin accuracy``, ``twin chapter5``):

* never over a campaign's own files (``results.nc``, ``analysis.nc``, ``spec.json``, the lock, anything under
  ``chunks/`` or ``corrupt/`` of a campaign directory), not even with ``--force``; the one exception is the
  command whose product the file is (``twin campaign analyze --force`` replaces ``analysis.nc``);
* never over one of the command's own inputs;
* never over any other existing file without ``--force``.

Files are written with the permissions the umask allows (as ``open()`` would create them), not the 0600 of a
temporary file, so a team sharing a directory can read them.
"""

from __future__ import annotations

import errno
import os
import shutil
import tempfile
from pathlib import Path

#: Files of a campaign directory (the layout of :mod:`campaigns.runner.storage`) that no command writes over.
CAMPAIGN_FILES = ("results.nc", "analysis.nc", "spec.json", ".lock")
#: Subdirectories of a campaign directory whose every file belongs to the campaign.
CAMPAIGN_DIRS = ("chunks", "corrupt")
#: The netCDF conventions every data file declares (``Conventions`` attribute).
CONVENTIONS = "CF-1.11"


class CampaignError(RuntimeError):
    """The campaign cannot proceed (e.g. an output directory holding another spec's results)."""


class CampaignInterrupted(CampaignError):
    """Ctrl-C or SIGTERM stopped a campaign cleanly: its workers ended, its lock released, its finished chunks kept.

    Attributes
    ----------
    out_dir : Path
    kept, total : int
        Runs with a record on disk, and the campaign's runs.
    signal_name : str
        ``"Ctrl-C"`` or ``"SIGTERM"``.
    """

    def __init__(self, out_dir, kept: int, total: int, signal_name: str):
        self.out_dir, self.kept, self.total, self.signal_name = Path(out_dir), kept, total, signal_name
        super().__init__(f"stopped by {signal_name}: {kept} of {total} runs are kept in {out_dir}; the same "
                         "command with --resume runs the others")


def is_campaign_dir(directory: Path) -> bool:
    """Whether ``directory`` holds a campaign: its ``spec.json`` or lock, or a ``chunks/<spec hash>/`` directory."""
    if (directory / "spec.json").is_file() or (directory / ".lock").is_file():
        return True
    try:
        return any(p.is_dir() for p in (directory / "chunks").iterdir())
    except OSError:
        return False


def campaign_file(path: str | Path) -> str | None:
    """What ``path`` is to a campaign, in words (e.g. ``"the results.nc of the campaign in out/thesis"``), or None."""
    for candidate in dict.fromkeys((Path(path).absolute(), Path(path).resolve())):
        parent = candidate.parent
        if candidate.name in CAMPAIGN_FILES and is_campaign_dir(parent):
            return f"the {candidate.name} of the campaign in {parent}"
        for ancestor in (parent, *parent.parents):
            if ancestor.name in CAMPAIGN_DIRS and is_campaign_dir(ancestor.parent):
                return f"a file of the campaign in {ancestor.parent} (its {ancestor.name}/)"
    return None


def check_output(out: str | Path, inputs=(), *, force: bool = False, product: str | None = None) -> Path:
    """The one rule of every command that writes ``out`` (module docstring); checked before any work.

    Parameters
    ----------
    out : str or Path
        The file the command will write.
    inputs : iterable of paths
        The command's input files (``None`` entries ignored): never written over.
    force : bool
        Replace an existing file (``--force``), unless it is an input or a campaign's own file.
    product : str, optional
        The campaign file this command makes (``"analysis.nc"`` for ``twin campaign analyze``): it may replace
        that one with ``force``.

    Raises
    ------
    CampaignError
        Naming the file, why it is refused and what to do.
    """
    out = Path(out)
    for given in inputs:
        if given is not None and Path(given).exists() and out.exists() and os.path.samefile(out, given):
            raise CampaignError(f"{out}: refusing to write the output over its own input; choose another --out")
    if out.is_dir():
        raise CampaignError(f"{out} is a directory; --out names the file to write")
    owned = campaign_file(out)
    if owned and out.name != product:
        raise CampaignError(f"{out} is {owned}; no command writes over a campaign's own files, even with --force. "
                            "Choose another --out")
    if out.exists() and not force:
        raise CampaignError(f"{out} already exists; pass --force to replace it or choose another --out")
    return out


def check_outputs(directory: str | Path, names, *, force: bool = False) -> Path:
    """:func:`check_output` for each file (or glob pattern) ``names`` a command writes in ``directory``."""
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():
        raise CampaignError(f"{directory} is not a directory; --out names the directory to write into")
    for name in names:
        for path in (sorted(directory.glob(name)) if any(c in name for c in "*?[") else [directory / name]):
            check_output(path, force=force)
    return directory


def _umask() -> int:
    """The process's umask, read without changing it (Linux: /proc/self/status), else by setting it back at once."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def size_text(n: float) -> str:
    """A size in bytes for a message, two significant digits ("970 kB", "1.4 MB"): two sizes that differ do not
    read alike."""
    for unit in ("B", "kB", "MB", "GB"):
        if n < 1000:
            return f"{n:.2g} {unit}" if n < 100 else f"{n:.0f} {unit}"
        n /= 1000
    return f"{n:.2g} TB"


def _free_space(directory: Path) -> str:
    try:
        return f"{size_text(shutil.disk_usage(directory).free)} free on {directory}"
    except OSError:
        return "free space unknown"


def atomic_write(path: Path, write) -> None:
    """Call ``write(tmp_path)`` then move the file onto ``path`` atomically.

    The file gets the permissions the umask allows (``0666 & ~umask``, as ``open()`` creates files), not
    the 0600 of the temporary file.

    Raises
    ------
    CampaignError
        If the file system refuses (read-only, full, missing directory) or the writer fails on the way
        (netCDF reports a full disk as an HDF error), naming ``path``; the temporary file is removed.
    """
    path = Path(path)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as exc:
        raise CampaignError(f"cannot write {path}: {exc.strerror or exc}") from exc
    os.close(fd)
    try:
        write(Path(tmp))
        os.chmod(tmp, 0o666 & ~_umask())
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        full = " (the disk is full)" if exc.errno in (errno.ENOSPC, errno.EDQUOT) else ""
        raise CampaignError(f"cannot write {path}: {exc.strerror or exc}{full}; {_free_space(path.parent)}. "
                            "Nothing was replaced") from exc
    except RuntimeError as exc:  # netCDF4/HDF5: "NetCDF: HDF error" when the disk fills while writing
        Path(tmp).unlink(missing_ok=True)
        raise CampaignError(f"cannot write {path}: {exc} (a full disk is the usual cause: "
                            f"{_free_space(path.parent)}). Nothing was replaced") from exc
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def cf_encoding(ds) -> dict:
    """netCDF encoding that keeps a dataset CF-clean: text coordinates (``dataset``, ``feature``, a data set's
    ``scene``, ...) as character arrays (CF 1.8, Sec. 6.1 labels: tools that check the monotonicity of numeric
    coordinate variables skip them, and xarray reads them back as string coordinates), no ``_FillValue`` on any other
    coordinate (CF 1.8, Sec. 2.5.1: coordinates have no missing values), 64-bit integers stored as 32-bit where they
    fit (netCDF classic types)."""
    import numpy as np

    encoding = {}
    for name, variable in ds.variables.items():
        entry = {}
        if name in ds.coords:
            entry.update({"dtype": "S1"} if variable.dtype.kind in "OUS" else {"_FillValue": None})
        if variable.dtype == np.int64 and (variable.size == 0 or (
                np.iinfo(np.int32).min <= variable.values.min() and variable.values.max() <= np.iinfo(np.int32).max)):
            entry["dtype"] = "int32"
        encoding[name] = entry
    return encoding


def write_netcdf(ds, path: str | Path, *, title: str, history: str) -> Path:
    """Write ``ds`` atomically as a CF-clean netCDF4 file (:func:`cf_encoding`) with ``Conventions``, ``title`` and a
    ``history`` line (appended to the dataset's own history, CF 2.6.2).

    A run's ``time`` stays what :func:`twin.simulate` makes it, seconds since the start of the test procedure in
    units ``s``: no reference date, so a reader plots the signals against seconds, not against 1970 dates
    (``docs/campaigns.md``, "The data files in other tools")."""
    from datetime import UTC, datetime

    path = Path(path)
    ds = ds.copy()
    stamp = datetime.now(UTC).isoformat(timespec="seconds")
    previous = str(ds.attrs.get("history", "")).strip()
    ds.attrs.update(Conventions=CONVENTIONS, title=ds.attrs.get("title") or title,
                    history="\n".join(line for line in (previous, f"{stamp}: {history}") if line))
    encoding = cf_encoding(ds)
    atomic_write(path, lambda tmp: ds.to_netcdf(tmp, engine="netcdf4", encoding=encoding))
    return path
