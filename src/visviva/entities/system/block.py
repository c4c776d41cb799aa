"""The named systems' block of the state: their generalized coordinates, one system after the
other, after the particles' (:mod:`visviva.model.scene_system` lays the state out)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ...ode.problems import Problem
from .systems import SYSTEMS

__all__ = ["SystemInstance"]


@dataclass(frozen=True, eq=False)
class SystemInstance:
    """A named system of the scene with its parameter values (defaults filled in).

    Attributes:
        name: Entity name.
        system: The system's type name (``"pendulum"``, ...).
        parameters: Parameter values.
        entity: The entity's index in the scene.
        offset: Index of its first coordinate among the scene's generalized coordinates.
        problem: Its problem (initial state, equations of motion).
    """

    name: str
    system: str
    parameters: Mapping[str, float]
    entity: int
    offset: int
    problem: Problem = field(repr=False)

    @property
    def size(self) -> int:
        """Number of its coordinates."""
        return self.problem.size

    @property
    def conservative(self) -> bool:
        """True if its exact dynamics conserve the energy it reports."""
        return SYSTEMS[self.system].conservative(self.parameters)

    @property
    def drawn(self) -> bool:
        """True if it has a picture (points to draw)."""
        return SYSTEMS[self.system].draw is not None

    @property
    def gravitating(self) -> bool:
        """True for a system of gravitating bodies: its coordinates are its picture."""
        return SYSTEMS[self.system].bodies

    @property
    def edges(self) -> tuple[tuple[int, int], ...] | None:
        """The lines between its picture's points, if any."""
        return SYSTEMS[self.system].edges

    def points(self, gravity: np.ndarray, parts: tuple[np.ndarray, ...]) -> np.ndarray | None:
        """Its picture for frames of its parts (``(frames, n)`` each): ``(frames, P, 3)`` [m]."""
        draw = SYSTEMS[self.system].draw
        return None if draw is None else draw(self.parameters, gravity, parts)
