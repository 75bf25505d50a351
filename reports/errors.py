"""The error a report raises for missing, corrupt or inconsistent input."""

from __future__ import annotations

from pathlib import Path


class ReportError(RuntimeError):
    """A report cannot be generated from the given files.

    Parameters
    ----------
    path : str or Path
        The file (or directory) at fault.
    problem : str
        What is wrong with it, in words a user can act on.
    """

    def __init__(self, path: str | Path, problem: str):
        self.path = Path(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")
