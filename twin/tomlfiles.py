"""One TOML inheritance for the project's data files.

A scene names its parent with ``base = "nominal"``, a campaign spec with ``extends = "other.toml"``; both
mean the same: the file holds the parent's fields, overridden by its own, tables merged key by key (a data
set's scene overrides one condition and keeps the others) and every other field replaced.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path


def merge(parent: dict, child: dict) -> dict:
    """``child`` over ``parent``: a table present in both is merged key by key, any other field replaced."""
    merged = dict(parent)
    for key, value in child.items():
        both_tables = isinstance(value, dict) and isinstance(merged.get(key), dict)
        merged[key] = {**merged[key], **value} if both_tables else value
    return merged


def read_inheriting(path: Path, key: str, read: Callable[[Path], dict],
                    locate: Callable[[Path, object, tuple[Path, ...]], Path],
                    seen: tuple[Path, ...] = ()) -> dict:
    """Read a file and the chain of parents its ``key`` field names, merged (:func:`merge`).

    Parameters
    ----------
    path : Path
        The file.
    key : str
        The field naming the parent (``"base"``, ``"extends"``); removed from the result.
    read : callable
        ``read(path) -> dict``: parses one file (raising the caller's error, naming the file).
    locate : callable
        ``locate(path, parent, seen) -> Path``: the parent's file; raises the caller's error when the
        parent is not a file or is in ``seen`` (the files already on the chain: a cycle).
    seen : tuple of Path
        The resolved paths of the files that inherit from ``path``.
    """
    data = read(path)
    parent = data.pop(key, None)
    if parent is None:
        return data
    parent_path = locate(path, parent, seen + (path.resolve(),))
    return merge(read_inheriting(parent_path, key, read, locate, seen + (path.resolve(),)), data)
