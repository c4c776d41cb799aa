"""The mutable storage of one run: what a shared Model and a stateless integrator keep per run.

A Model is shared: many simulations of it may step at once, in threads or one after the other
in turns, and integrators are registered singletons. So neither may hold anything that changes
while a run goes on — scratch arrays, neighbour grids, the warm starts of contact solvers,
multigrid hierarchies, factorized matrices. Each run has a :class:`Workspace` instead (as
MuJoCo's ``mjData`` beside its ``mjModel``), made with the run's system
(:attr:`~visviva.ode.system.SecondOrderSystem.workspace`) and handed to every force, stage and
integrator that steps it; each keeps its storage there under its own key::

    scratch = work.get(self, lambda: _Scratch(self.count))

The storage of a run is never seen by another run, so two simulations of one model give the
bits of each run done alone.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

__all__ = ["Workspace"]

T = TypeVar("T")


class Workspace:
    """One run's storage, one entry per owner (a force, a stage, an integrator).

    Not safe to share between threads: each run steps in one thread at a time, with its own.
    """

    __slots__ = ("_entries",)

    def __init__(self) -> None:
        # id(owner) -> (owner, storage): the owner is kept so that its id is never reused by
        # another object while the entry lives.
        self._entries: dict[int, tuple[object, object]] = {}

    def get(self, owner: object, make: Callable[[], T]) -> T:
        """The storage of ``owner`` in this run, made by ``make()`` on first use."""
        entry = self._entries.get(id(owner))
        if entry is None or entry[0] is not owner:
            entry = (owner, make())
            self._entries[id(owner)] = entry
        return entry[1]  # type: ignore[return-value]

    def peek(self, owner: object) -> object | None:
        """The storage of ``owner`` if it has made any, else ``None`` (for inspection)."""
        entry = self._entries.get(id(owner))
        return entry[1] if entry is not None and entry[0] is owner else None

    def __len__(self) -> int:
        return len(self._entries)
