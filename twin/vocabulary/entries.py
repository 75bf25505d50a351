"""What a component declares: its entries (states, constants, signals, work rows), each with unit and meaning."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Entry:
    """A state, constant, signal or work row: identifier (``{n}``: the instance number), SI unit, meaning (one per
    instance where there are several, so each has its own ``long_name``), for a constant the parameter(s) it copies
    (one per instance; empty when it is derived by the component or :func:`twin.engine.model.build_model`), and for
    a work row how many rows it spans (a per-nut row names its first nut's row, the next is nut 2's)."""

    name: str
    unit: str
    description: str | tuple[str, ...]
    parameter: str | tuple[str, ...] = ""
    rows: int = 1

    def meaning(self, n: int) -> str:
        """The description of instance ``n`` (0-based)."""
        return self.description if isinstance(self.description, str) else self.description[n]


@dataclass(frozen=True)
class Component:
    """A part of the bench and what it contributes to the layouts: its continuous states, the model constants it
    reads, the signals it records (each of these once per instance) and the work rows it leaves for the rest of
    the engine in one right-hand-side evaluation (:class:`twin.layout.W`; not per instance: ``rows`` says how
    many)."""

    name: str
    states: tuple[Entry, ...] = ()
    constants: tuple[Entry, ...] = ()
    signals: tuple[Entry, ...] = ()
    work: tuple[Entry, ...] = ()
    instances: int = 1


def entry(name: str, unit: str, description: str | tuple[str, ...], parameter: str | tuple[str, ...] = "") -> Entry:
    """A state, constant or signal (:class:`Entry`)."""
    return Entry(name, unit, description, parameter)


def work(name: str, unit: str, description: str, rows: int = 1) -> Entry:
    """A work row (:class:`Entry` with ``rows``)."""
    return Entry(name, unit, description, rows=rows)
