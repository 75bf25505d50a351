"""numba's on-disk cache keyed on the project's source, so compiled code is never stale.

numba's ``cache=True`` checks only the time stamp and size of the file that
*defines* a compiled function. When a function it calls from another module
changes (say ``twin.physics.coupling.elasto_backlash``, called by
``twin.engine.plant.transmitted_torque``), the caller's cached machine code
still holds the old callee, and a run silently executes the old physics.

:func:`configure` points ``NUMBA_CACHE_DIR`` at a directory named after a hash
of every ``.py`` file of the packages numba compiles from (``twin``, ``sensors``
and ``numerics``): any source edit selects a fresh, empty cache directory. It must
run before the first ``@njit(cache=True)`` decorator executes (numba fixes a
function's cache location when it is decorated), so ``numerics/__init__.py``
calls it before importing anything compiled, ``sensors`` imports ``numerics``
first and ``twin`` imports ``sensors`` first. It lives in ``numerics``, the bottom
layer, so that every compiled package can use it without an upward import.

Child processes (dask workers, the campaign sandbox) inherit the environment
variable and, importing ``twin`` themselves, recognise the directory as
already keyed; they use the same cache. The base directory is the user's
``NUMBA_CACHE_DIR`` if set, otherwise ``$XDG_CACHE_HOME/benchtwin/numba``
(``~/.cache/benchtwin/numba``). Directories of older source versions are left
in place (a few MB each); delete the base directory to reclaim the space.
"""

import hashlib
import os
from pathlib import Path

#: Prefix of the per-source-hash cache directories.
KEY_PREFIX = "benchtwin-"
#: Packages whose modules hold ``numba`` functions (directories next to ``numerics``).
COMPILED_PACKAGES = ("twin", "sensors", "numerics")


def source_hash(root: Path | None = None) -> str:
    """SHA-256 (first 16 hex digits) of the path and content of every ``.py`` file of the compiled packages.

    Parameters
    ----------
    root : Path, optional
        Directory holding the packages; by default the one holding this ``numerics`` package.
    """
    root = Path(__file__).resolve().parent.parent if root is None else root
    digest = hashlib.sha256()
    for package in COMPILED_PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(b"\0")
            digest.update(path.read_bytes())
            digest.update(b"\0")
    return digest.hexdigest()[:16]


def cache_directory(source_key: str, environment: dict | None = None) -> Path:
    """The cache directory for sources hashing to ``source_key``, under the base the environment names."""
    environment = os.environ if environment is None else environment
    configured = environment.get("NUMBA_CACHE_DIR", "")
    if configured:
        base = Path(configured)
        if base.name.startswith(KEY_PREFIX):  # already keyed (by a parent process): use its base
            base = base.parent
    else:
        xdg = environment.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        base = Path(xdg) / "benchtwin" / "numba"
    return base / f"{KEY_PREFIX}{source_key}"


def configure() -> Path:
    """Point numba's cache at the directory of the current sources; idempotent. Returns the directory."""
    directory = cache_directory(source_hash())
    if os.environ.get("NUMBA_CACHE_DIR") != str(directory):
        os.environ["NUMBA_CACHE_DIR"] = str(directory)
        # numba may already be imported (by the caller); make it re-read the environment now.
        from numba.core import config

        config.reload_config()
    return directory
