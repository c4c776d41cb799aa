"""Immutable snapshots of a system: the time and the state arrays.

Integrators map one state to the next (``Integrator.step(system, state, dt) -> state``) and keep
nothing between calls; whatever a method wants to carry from one step to the next (the
derivative it already evaluated at the new state) travels inside the state, where it cannot go
stale: a state with different values is a different object, built without that cache.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

__all__ = ["FirstOrderState", "SecondOrderState", "State"]


@dataclass(frozen=True, eq=False)
class FirstOrderState:
    """State of ``y' = f(t, y)``.

    Attributes:
        t: Time [s].
        y: State vector, shape ``(n,)`` or ``(batch, n)``.
        rate: ``f(t, y)`` if an integrator already evaluated it at exactly this state (reused
            by methods whose first stage needs it), else ``None``.
    """

    t: float
    y: np.ndarray
    rate: np.ndarray | None = None

    @property
    def parts(self) -> tuple[np.ndarray, ...]:
        """The state arrays as a tuple, ``(y,)``, for methods written for any problem kind."""
        return (self.y,)

    def from_parts(self, t: float, parts: tuple[np.ndarray, ...]) -> FirstOrderState:
        """A new state of the same kind at time ``t`` with arrays ``parts`` and no cache."""
        (y,) = parts
        return FirstOrderState(t, y)

    def at_time(self, t: float) -> FirstOrderState:
        """The same state stamped with time ``t`` (the loop's exact time from its counter)."""
        return replace(self, t=t)

    def with_derivative(self, derivative: tuple[np.ndarray, ...]) -> FirstOrderState:
        """The same state carrying its derivative ``(f(t, y),)``, evaluated by the caller."""
        return replace(self, rate=derivative[0])


@dataclass(frozen=True, eq=False)
class SecondOrderState:
    """State of ``M q'' = F(t, q, v)`` kept split so that symplectic methods are real.

    Attributes:
        t: Time [s].
        q: Generalized coordinates, shape ``(n,)`` or ``(batch, n)``.
        v: Generalized velocities ``dq/dt``, same shape as ``q``.
        acceleration: ``q''`` at exactly this ``(t, q, v)`` if an integrator already evaluated
            it, else ``None``.
    """

    t: float
    q: np.ndarray
    v: np.ndarray
    acceleration: np.ndarray | None = None

    @property
    def parts(self) -> tuple[np.ndarray, ...]:
        """The state arrays as a tuple, ``(q, v)``."""
        return (self.q, self.v)

    def from_parts(self, t: float, parts: tuple[np.ndarray, ...]) -> SecondOrderState:
        """A new state of the same kind at time ``t`` with arrays ``parts`` and no cache."""
        q, v = parts
        return SecondOrderState(t, q, v)

    def at_time(self, t: float) -> SecondOrderState:
        """The same state stamped with time ``t`` (the loop's exact time from its counter)."""
        return replace(self, t=t)

    def with_derivative(self, derivative: tuple[np.ndarray, ...]) -> SecondOrderState:
        """The same state carrying its derivative ``(v, q'')``, evaluated by the caller."""
        return replace(self, acceleration=derivative[1])


State = FirstOrderState | SecondOrderState
