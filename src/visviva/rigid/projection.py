"""The projection stage of rigid bodies: orientations back onto unit quaternions.

A Runge–Kutta step moves a quaternion by ``q + h Σ b_i q'_i``, a straight line off the unit
sphere (its length grows by about ``(h|ω|)²/8`` a step), and a rotation matrix built from a
quaternion that is not unit is not a rotation. After each step this stage divides every
orientation by its length, as the lecture's explicit Euler does (seed 003). The symplectic
methods' drift turns quaternions by exact rotations: they come out unit to round-off, and the
stage leaves such a state as it is.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from ..ode.stage import Phase
from ..ode.state import State

if TYPE_CHECKING:
    from ..ode.workspace import Workspace

__all__ = ["BodyProjection"]

#: Largest | |q| − 1 | left alone: a few units of round-off.
UNIT_TOLERANCE = 8 * np.finfo(np.float64).eps


class BodyProjection:
    """Renormalize the ``body_orientation`` part of a state after every step.

    Args:
        count: Number of bodies.
    """

    phase: ClassVar[Phase] = Phase.CONSTRAINTS
    #: After the handles (which hold particles, not bodies: the two never meet).
    order: ClassVar[int] = 1
    compiled: ClassVar[bool] = False
    #: Renormalizing keeps the rotation a quaternion stands for: it does not change the energy.
    changes_energy: ClassVar[bool] = False
    kills_particles: ClassVar[bool] = False

    def __init__(self, count: int) -> None:
        self.count = count

    def carried_start(self) -> dict[str, np.ndarray]:
        """None: it carries nothing in the state."""
        return {}

    def apply(self, before: State, after: State, h: float, work: Workspace) -> State:
        """``after`` with each orientation divided by its length (``after`` itself if they are
        unit to round-off)."""
        view = after.layout.view("body_orientation")
        q, v = after.parts
        orientation = view.of(after.parts)
        length = np.sqrt(np.einsum("ij,ij->i", orientation, orientation))
        if np.all(np.abs(length - 1.0) <= UNIT_TOLERANCE):
            return after
        projected = q.copy()
        view.of((projected, v))[...] = orientation / length[:, None]
        return after.from_parts(after.t, (projected, v))
