"""Writing campaign files safely: the error of a campaign that cannot proceed, and the atomic write.

A module of its own, below the storage layout (:mod:`campaigns.storage`), so that the analysis and
the audits can write their files without importing the spec, the bench adapter and the twin.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


class CampaignError(RuntimeError):
    """The campaign cannot proceed (e.g. an output directory holding another spec's results)."""



def atomic_write(path: Path, write) -> None:
    """Call ``write(tmp_path)`` then move the file onto ``path`` atomically.

    Raises
    ------
    CampaignError
        If the file system refuses (read-only, full, missing directory), naming ``path``.
    """
    path = Path(path)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as exc:
        raise CampaignError(f"cannot write {path}: {exc.strerror or exc}") from exc
    os.close(fd)
    try:
        write(Path(tmp))
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise CampaignError(f"cannot write {path}: {exc.strerror or exc}") from exc
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
