"""Error types of the bench twin.

Every input error lists *all* problems found, each naming the offending field
and what is allowed, so a user fixes a spec in one pass.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable


def did_you_mean(name: str, known: Iterable[str], *, cutoff: float = 0.75) -> str:
    """``"did you mean 'motor.inertia'?"`` when ``name`` is a likely misspelling of a known name, else ``""``.

    The closest names by :func:`difflib.get_close_matches` (ratio of matching characters, at least ``cutoff``), the
    part after the last dot compared too so that ``motor.inertai`` finds ``motor.inertia`` among many long names.
    """
    known = list(dict.fromkeys(known))
    matches = difflib.get_close_matches(name, known, n=3, cutoff=cutoff)
    if not matches and "." in name:  # the group spelt right, the key wrong: compare the keys of that group
        group, key = name.rsplit(".", 1)
        keys = {k.rsplit(".", 1)[1]: k for k in known if k.startswith(group + ".")}
        matches = [keys[k] for k in difflib.get_close_matches(key, list(keys), n=3, cutoff=cutoff)]
    if not matches:
        return ""
    return "did you mean " + " or ".join(repr(m) for m in matches) + "?"


class InputError(ValueError):
    """Invalid user input; ``problems`` holds one message per offending field."""

    def __init__(self, what: str, problems: list[str]):
        self.problems = list(problems)
        lines = "\n".join(f"  - {p}" for p in self.problems)
        super().__init__(f"invalid {what} ({len(self.problems)} problem(s)):\n{lines}")


class ParameterError(InputError):
    """A parameter file or a parameter override is invalid."""

    def __init__(self, problems: list[str]):
        super().__init__("parameters", problems)


class SceneError(InputError):
    """A scene (test procedure) is invalid."""

    def __init__(self, problems: list[str]):
        super().__init__("scene", problems)


class OptionError(InputError):
    """A simulation option is invalid: a field of :class:`twin.Solver` (raised when it is made) or an argument of
    :func:`twin.simulate` (raised before the run)."""

    def __init__(self, problems: list[str]):
        super().__init__("simulation options", problems)


class SimulationFailed(RuntimeError):
    """A run diverged or failed; raised by ``simulate(..., throw=True)``."""

    def __init__(self, status: str, reason: str, t_reached: float):
        self.status = status
        self.reason = reason
        self.t_reached = t_reached
        super().__init__(f"simulation {status} at t = {t_reached:.6g} s: {reason}")
