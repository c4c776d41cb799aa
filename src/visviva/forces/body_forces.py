"""Forces and torques on rigid bodies: gravity and damping.

The protocol of :mod:`.base` for bodies: a force *adds* the force [N] through each body's
centre of mass and the torque [N·m] about it, both in the world frame, into ``(B, 3)`` arrays
(``accumulate_wrench``), and reports its potential energy [J]. It reads the bodies' state
``(x, q, P, L)``: centres of mass ``(B, 3)`` [m], orientations ``(B, 4)``, momenta ``(B, 3)``
[kg·m/s] and angular momenta ``(B, 3)`` [kg·m²/s] (:mod:`visviva.rigid.motion`).

A force ``f`` applied at a point ``p`` of a body adds ``f`` to its force and ``(p − x) × f``
to its torque (:func:`wrench_at`); a force through the centre of mass turns nothing.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar, Protocol

import numpy as np

from .fields import vector

__all__ = ["BodyDamping", "BodyForce", "BodyGravity", "wrench_at"]


class BodyForce(Protocol):
    """What the model needs from a force on rigid bodies."""

    conservative: ClassVar[bool]
    velocity_dependent: ClassVar[bool]

    def accumulate_wrench(
        self,
        t: float,
        x: np.ndarray,
        q: np.ndarray,
        momentum: np.ndarray,
        angular_momentum: np.ndarray,
        force: np.ndarray,
        torque: np.ndarray,
    ) -> None:
        """Add the force [N] and the torque about the centre of mass [N·m] on every body to
        ``force`` and ``torque``, ``(B, 3)`` each."""
        ...

    def potential(self, t: float, x: np.ndarray) -> float:
        """Potential energy [J] of the bodies with centres of mass ``x`` ``(B, 3)``."""
        ...


def wrench_at(
    x: np.ndarray, points: np.ndarray, forces: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The force and the torque about the centres of mass ``x`` ``(B, 3)`` [m] of forces
    ``forces`` ``(B, 3)`` [N] applied at world points ``points`` ``(B, 3)`` [m]: ``f`` and
    ``τ = (p − x) × f``."""
    forces = np.asarray(forces, dtype=np.float64)
    return forces.copy(), np.cross(np.asarray(points, dtype=np.float64) - x, forces)


class BodyGravity:
    """Uniform gravity on the bodies: ``F = M g`` through the centre of mass, no torque;
    ``U = −Σ M g·x``.

    Args:
        gravity: ``g`` [m/s²], ``(3,)``.
        mass: ``(B,)`` masses [kg].
    """

    conservative = True
    velocity_dependent = False

    def __init__(self, gravity: Sequence[float], mass: np.ndarray) -> None:
        self.gravity = vector("gravity", gravity, unit="m/s²")
        self._weight = np.asarray(mass, dtype=np.float64)[:, None] * self.gravity[None, :]

    def accumulate_wrench(self, t, x, q, momentum, angular_momentum, force, torque) -> None:  # type: ignore[no-untyped-def]
        """Add ``M g`` [N] to ``force`` (no torque)."""
        force += self._weight

    def potential(self, t: float, x: np.ndarray) -> float:
        """``U = −Σ M g·x`` [J]."""
        return -float(np.einsum("ij,ij->", x, self._weight))


class BodyDamping:
    """Damping of the momenta at constant rates: ``F = −γ P``, ``τ = −γ' L`` (the momenta decay
    as ``e^(−γt)`` without other forces; the angular one whatever the body's shape).

    Args:
        linear: ``(B,)`` γ [1/s].
        angular: ``(B,)`` γ' [1/s].
    """

    conservative = False
    velocity_dependent = True

    def __init__(self, linear: np.ndarray, angular: np.ndarray) -> None:
        self.linear = np.asarray(linear, dtype=np.float64)[:, None]
        self.angular = np.asarray(angular, dtype=np.float64)[:, None]

    def accumulate_wrench(self, t, x, q, momentum, angular_momentum, force, torque) -> None:  # type: ignore[no-untyped-def]
        """Add ``−γ P`` to ``force`` and ``−γ' L`` to ``torque``."""
        force -= self.linear * momentum
        torque -= self.angular * angular_momentum

    def potential(self, t: float, x: np.ndarray) -> float:
        """0: damping stores no energy."""
        return 0.0
