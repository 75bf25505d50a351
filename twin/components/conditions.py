"""What a component reads of the test procedure: its conditions (:meth:`twin.scenes.Scene.condition`).

Stated as a ``Protocol`` so that the components, which the loop design imports, sit below the scenes package.
"""

from __future__ import annotations

from typing import Protocol


class Conditions(Protocol):
    """A scene's conditions by name, in SI units (:data:`twin.scenes.CONDITIONS`)."""

    def condition(self, name: str): ...
