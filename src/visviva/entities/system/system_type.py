"""What a named system is: its parameters, how it builds its problem and how it draws itself."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from ...ode.problems import Problem

__all__ = ["Drawing", "Parameter", "SystemType"]


@dataclass(frozen=True)
class Parameter:
    """One parameter of a named system.

    Attributes:
        default: Value used when the scene does not give one.
        unit: SI unit, for messages and the schema.
        description: One line.
        positive: The value must be > 0.
        integer: The value must be a whole number (a count).
        minimum: Smallest value accepted (e.g. 0 for a length that may vanish).
        maximum: Largest value accepted (counts are capped before anything is allocated).
        initial: The value is an initial condition (an angle, a speed at the start), not part
            of the equations of motion: systems that differ only in such values share their
            derived, compiled equations and can advance side by side in one batched state.
    """

    default: float
    unit: str
    description: str
    positive: bool = False
    integer: bool = False
    minimum: float | None = None
    maximum: float | None = None
    initial: bool = False


#: Draws frames of a system: ``(values, gravity, parts)`` with ``parts`` = ``(q, v)`` or ``(y,)``
#: with a leading frame axis → points ``(frames, P, 3)`` [m].
Drawing = Callable[[Mapping[str, float], np.ndarray, tuple[np.ndarray, ...]], np.ndarray]


@dataclass(frozen=True)
class SystemType:
    """A named system: its parameters, its problem and its picture.

    Attributes:
        name: Name used in scene files.
        summary: One line.
        parameters: Parameter name → :class:`Parameter`.
        build: ``build(values, gravity)`` → the problem; ``gravity`` [m/s²] is the world's.
        draw: Maps recorded frames to points, or ``None`` if the system has no picture.
        edges: Point-index pairs drawn as lines, or ``None``.
        bodies: The coordinates are the positions of bodies, ``(x, y, z)`` per body, and so
            are the picture: recordings keep them once, as ``system_points`` and
            ``system_velocity``.
        dissipation: Name of the parameter that makes the system lose energy when it is not
            zero (a damping coefficient), or ``None`` if it always conserves energy.
    """

    name: str
    summary: str
    parameters: Mapping[str, Parameter]
    build: Callable[[Mapping[str, float], np.ndarray], Problem]
    draw: Drawing | None = None
    edges: tuple[tuple[int, int], ...] | None = None
    dissipation: str | None = None
    bodies: bool = False

    def conservative(self, values: Mapping[str, float]) -> bool:
        """True if the system with these parameter values conserves its energy."""
        return self.dissipation is None or values[self.dissipation] == 0.0
