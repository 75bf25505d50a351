"""Error types of the bench twin.

Every input error lists *all* problems found, each naming the offending field
and what is allowed, so a user fixes a spec in one pass.
"""

from __future__ import annotations


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
    """A simulation option is invalid."""

    def __init__(self, problems: list[str]):
        super().__init__("simulation options", problems)


class SimulationFailed(RuntimeError):
    """A run diverged or failed; raised by ``simulate(..., throw=True)``."""

    def __init__(self, status: str, reason: str, t_reached: float):
        self.status = status
        self.reason = reason
        self.t_reached = t_reached
        super().__init__(f"simulation {status} at t = {t_reached:.6g} s: {reason}")
