"""Immutable snapshots of a system: the time and its named parts.

A :class:`State` holds two kinds of arrays:

* the **integrated** arrays, ``parts``, that time integrators advance: ``(y,)`` for
  ``y' = f(t, y)`` and ``(q, v)`` for ``M q'' = F(t, q, v)``, kept split so that symplectic
  methods are real (seed 001). Integrators see only these and never know what they hold.
* the **carried** arrays, that no integrator touches and the post-step stages change: which
  particles are alive, their ages, an emitter's count of births.

Every part has a name. A :class:`Layout` says where each named part lives: a scene's
``particle_position`` is a ``(N, 3)`` view of the first ``3N`` entries of ``q`` (no copy), a
pendulum's ``generalized_position`` the entries after it, a plain problem's ``q`` the whole
array. The loop, the watch, the recorder and the analysis tools go through the names
(:meth:`State.named`); none of them asks what kind of system it runs.

Integrators map one state to the next (``Integrator.step(system, state, dt) -> state``) and keep
nothing between calls; whatever a method wants to carry from one step to the next (the
derivative it already evaluated at the new state) travels inside the state, where it cannot go
stale: a state with different values is a different object, built without that cache.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType

import numpy as np

__all__ = ["Layout", "PartView", "State"]

_NOTHING: Mapping[str, np.ndarray] = MappingProxyType({})


@dataclass(frozen=True)
class PartView:
    """Where a named part lives inside the integrated arrays.

    Attributes:
        name: The part's name (``"particle_position"``, ``"q"``, ...).
        array: Index of the integrated array that holds it (0 for ``y`` or ``q``, 1 for ``v``).
        start: First entry along the array's last axis, or ``None`` for the whole array.
        stop: One past the last entry (with ``start``).
        shape: Shape of the view (for instance ``(N, 3)``), or ``None`` to keep the slice's.
        unit: SI unit of the values, for messages and recordings.
    """

    name: str
    array: int
    start: int | None = None
    stop: int | None = None
    shape: tuple[int, ...] | None = None
    unit: str = ""

    def of(self, parts: tuple[np.ndarray, ...]) -> np.ndarray:
        """This part of the integrated arrays ``parts``, as a view (never a copy)."""
        values = parts[self.array]
        if self.start is not None:
            values = values[..., self.start : self.stop]
        if self.shape is not None:
            values = values.reshape(self.shape)
        return values

    def locate(self, flat_index: int) -> tuple[int, ...]:
        """The index inside this part of entry ``flat_index`` of the slice."""
        if self.shape is None:
            return (flat_index,)
        return tuple(int(i) for i in np.unravel_index(flat_index, self.shape))


@dataclass(frozen=True)
class Layout:
    """Names and roles of a state's integrated arrays.

    Attributes:
        second_order: The integrated arrays are ``(q, v)`` with ``q' = v`` (else ``(y,)``).
        views: The named parts, in a fixed order, each a view into one integrated array.
    """

    second_order: bool
    views: tuple[PartView, ...]

    @classmethod
    def first_order(cls) -> Layout:
        """A plain first-order problem: one part ``y``."""
        return _FIRST_ORDER

    @classmethod
    def positions_and_velocities(cls) -> Layout:
        """A plain second-order problem: parts ``q`` and ``v``."""
        return _SECOND_ORDER

    def view(self, name: str) -> PartView:
        """The view called ``name``; ``KeyError`` if there is none."""
        for view in self.views:
            if view.name == name:
                return view
        raise KeyError(name)

    def locate(self, array: int, flat_index: int) -> tuple[str, tuple[int, ...]]:
        """The named part and the index inside it of entry ``flat_index`` along the last axis
        of integrated array ``array``."""
        for view in self.views:
            if view.array != array:
                continue
            if view.start is None:
                return view.name, (flat_index,)
            if view.start <= flat_index < view.stop:  # type: ignore[operator]
                return view.name, view.locate(flat_index - view.start)
        return f"parts[{array}]", (flat_index,)


_FIRST_ORDER = Layout(False, (PartView("y", 0),))
_SECOND_ORDER = Layout(True, (PartView("q", 0), PartView("v", 1)))


@dataclass(frozen=True, eq=False)
class State:
    """The state of a system at one time.

    Attributes:
        t: Time [s].
        parts: The integrated arrays: ``(y,)`` or ``(q, v)``; each ``(n,)`` for one system or
            ``(batch, n)`` for a batch.
        layout: The names of the parts (see :class:`Layout`).
        carried: Arrays that integrators pass on unchanged and stages update, by name.
        derivative: The time derivative of ``parts`` at exactly this state — ``(f(t, y),)`` or
            ``(v, q'')`` — if an integrator already evaluated it, else ``None``.

    Example:
        >>> import numpy as np
        >>> state = State(0.0, (np.zeros(3), np.ones(3)), Layout.positions_and_velocities())
        >>> state["v"].tolist(), state.names()
        ([1.0, 1.0, 1.0], ['q', 'v'])
    """

    t: float
    parts: tuple[np.ndarray, ...]
    layout: Layout = field(default=_FIRST_ORDER)
    carried: Mapping[str, np.ndarray] = field(default_factory=lambda: _NOTHING)
    derivative: tuple[np.ndarray, ...] | None = None

    @property
    def y(self) -> np.ndarray:
        """The state vector ``y`` of a first-order state (the only integrated array)."""
        return self.parts[0]

    @property
    def q(self) -> np.ndarray:
        """Coordinates ``q`` of a second-order state (the first integrated array)."""
        return self.parts[0]

    @property
    def v(self) -> np.ndarray:
        """Velocities ``v = q'`` of a second-order state (the second integrated array)."""
        return self.parts[1]

    @property
    def acceleration(self) -> np.ndarray | None:
        """``q''`` at this state if an integrator already evaluated it, else ``None``."""
        return None if self.derivative is None else self.derivative[-1]

    def __getitem__(self, name: str) -> np.ndarray:
        if name in self.carried:
            return self.carried[name]
        try:
            return self.layout.view(name).of(self.parts)
        except KeyError:
            raise KeyError(
                f"the state has no part {name!r}; parts: {', '.join(self.names())}"
            ) from None

    def names(self) -> list[str]:
        """Every part's name: the integrated views, then the carried arrays."""
        return [view.name for view in self.layout.views] + list(self.carried)

    def named(self) -> Iterator[tuple[str, np.ndarray]]:
        """``(name, array)`` for every part, integrated views first (views, not copies)."""
        for view in self.layout.views:
            yield view.name, view.of(self.parts)
        yield from self.carried.items()

    def from_parts(
        self,
        t: float,
        parts: tuple[np.ndarray, ...],
        derivative: tuple[np.ndarray, ...] | None = None,
    ) -> State:
        """A new state at time ``t`` with integrated arrays ``parts`` and the same layout and
        carried arrays; ``derivative`` is its derivative if the caller evaluated it."""
        return State(t, parts, self.layout, self.carried, derivative)

    def at_time(self, t: float) -> State:
        """The same state stamped with time ``t`` (the loop's exact time from its counter)."""
        return replace(self, t=t)

    def with_derivative(self, derivative: tuple[np.ndarray, ...]) -> State:
        """The same state carrying its derivative, evaluated by the caller."""
        return replace(self, derivative=derivative)

    def with_carried(self, **arrays: np.ndarray) -> State:
        """The same state with carried arrays replaced or added."""
        return replace(self, carried=MappingProxyType(dict(self.carried) | arrays))
