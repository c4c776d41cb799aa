"""Forces and torques on rigid bodies: gravity, damping, pushes at points, anchors.

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
from dataclasses import dataclass
from typing import ClassVar, Protocol

import numpy as np

from ..geometry.quaternions import quaternion_matrix, quaternion_multiply
from .fields import vector
from .laws import GRAVITY, field_forces, law_row

__all__ = [
    "BodyAnchor",
    "BodyDamping",
    "BodyForce",
    "BodyGravity",
    "BodyLaw",
    "BodyPush",
    "wrench_at",
]


@dataclass(frozen=True, eq=False)
class BodyLaw:
    """A body force's compiled form: on body ``b``, ``F = M_b g − γ_b P``, ``τ = −γ'_b L``;
    the fused rigid step (:mod:`visviva.rigid.fused`) sums the forms of a scene's forces.

    Attributes:
        gravity: ``g`` [m/s²], ``(3,)``.
        mass: ``(B,)`` the masses ``g`` pulls [kg] (0 for a body gravity does not move).
        linear: ``(B,)`` γ [1/s].
        angular: ``(B,)`` γ' [1/s].
    """

    gravity: np.ndarray
    mass: np.ndarray
    linear: np.ndarray
    angular: np.ndarray


class BodyForce(Protocol):
    """What the model needs from a force on rigid bodies."""

    conservative: ClassVar[bool]
    velocity_dependent: ClassVar[bool]

    @property
    def compiled(self) -> BodyLaw | None:
        """Its compiled form, or ``None``: a scene with such a force takes the generic road."""
        ...

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

    def potential(self, t: float, x: np.ndarray, q: np.ndarray) -> float:
        """Potential energy [J] of the bodies with centres of mass ``x`` ``(B, 3)`` and
        orientations ``q`` ``(B, 4)``."""
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
    ``U = −Σ M g·x``. The law is the particles' (:data:`~.laws.GRAVITY`).

    Args:
        gravity: ``g`` [m/s²], ``(3,)``.
        mass: ``(B,)`` masses [kg] (0 for a body gravity does not move: a kinematic one).
    """

    conservative = True
    velocity_dependent = False

    def __init__(self, gravity: Sequence[float], mass: np.ndarray) -> None:
        self.gravity = vector("gravity", gravity, unit="m/s²")
        self.mass = np.asarray(mass, dtype=np.float64)
        self._weight = self.mass[:, None] * self.gravity[None, :]  # the potential's
        self._row = law_row(tuple(self.gravity))
        self._bodies = np.arange(self.mass.shape[0])

    @property
    def compiled(self) -> BodyLaw:
        """``F = M g``."""
        none = np.zeros_like(self.mass)
        return BodyLaw(self.gravity, self.mass, none, none)

    def accumulate_wrench(self, t, x, q, momentum, angular_momentum, force, torque) -> None:  # type: ignore[no-untyped-def]
        """Add ``M g`` [N] to ``force`` (no torque)."""
        field_forces(GRAVITY, self._row, self._bodies, x, momentum, self.mass, force)

    def potential(self, t: float, x: np.ndarray, q: np.ndarray) -> float:
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

    @property
    def compiled(self) -> BodyLaw:
        """``F = −γ P``, ``τ = −γ' L``."""
        linear = self.linear[:, 0]
        return BodyLaw(np.zeros(3), np.zeros_like(linear), linear, self.angular[:, 0])

    def accumulate_wrench(self, t, x, q, momentum, angular_momentum, force, torque) -> None:  # type: ignore[no-untyped-def]
        """Add ``−γ P`` to ``force`` and ``−γ' L`` to ``torque``."""
        force -= self.linear * momentum
        torque -= self.angular * angular_momentum

    def potential(self, t: float, x: np.ndarray, q: np.ndarray) -> float:
        """0: damping stores no energy."""
        return 0.0


def _world_points(q: np.ndarray, body: np.ndarray, x: np.ndarray, arm: np.ndarray) -> np.ndarray:
    """World positions ``x + R(q) arm`` [m] of points at ``arm`` ``(K, 3)`` from the centres
    of mass of bodies ``body`` ``(K,)`` (arms in the bodies' own axes)."""
    return x[body] + np.einsum("kij,kj->ki", quaternion_matrix(q[body]), arm)


class BodyPush:
    """Forces applied at points for a while: ``f`` [N] (world frame) at a point ``p`` of the
    body (fixed in it, turning with it) or of the world (fixed in space: a jet on a stand),
    from ``start`` to ``stop`` [s]; the body feels ``f`` and the torque ``(p − x) × f`` about
    its centre of mass (seed 002: a force off the centre of mass turns the body).

    Args:
        body: ``(K,)`` the body each push acts on.
        force: ``(K, 3)`` [N].
        arm: ``(K, 3)`` a body point from the body's centre of mass, in its own axes, or a
            world point [m].
        start, stop: ``(K,)`` when each push acts [s] (``stop`` may be ``inf``).
        world: ``(K,)`` which ``arm`` rows are world points (default: none).
    """

    conservative = False
    velocity_dependent = False
    #: No compiled form: a scene with it takes the generic road.
    compiled = None

    def __init__(self, body, force, arm, start, stop, world=None) -> None:  # type: ignore[no-untyped-def]
        self.body = np.asarray(body, dtype=np.int64)
        self.world = np.zeros(self.body.shape[0], bool) if world is None else np.asarray(world)
        self.force = np.asarray(force, dtype=np.float64).reshape(-1, 3)
        self.arm = np.asarray(arm, dtype=np.float64).reshape(-1, 3)
        self.start = np.asarray(start, dtype=np.float64)
        self.stop = np.asarray(stop, dtype=np.float64)

    def accumulate_wrench(self, t, x, q, momentum, angular_momentum, force, torque) -> None:  # type: ignore[no-untyped-def]
        """Add the pushes acting at ``t`` (``start ≤ t < stop``) and their torques. A time
        within 1e-9 (relative) below an end counts as that end: a step's start time, summed
        from its steps, may fall a rounding short of the push's, which would add or drop a
        whole step of it."""
        t = t + 1e-9 * max(1.0, abs(t))
        on = (self.start <= t) & (t < self.stop)
        if not on.any():
            return
        body = self.body[on]
        points = np.where(
            self.world[on, None], self.arm[on], _world_points(q, body, x, self.arm[on])
        )
        f, tau = wrench_at(x[body], points, self.force[on])
        np.add.at(force, body, f)
        np.add.at(torque, body, tau)

    def potential(self, t: float, x: np.ndarray, q: np.ndarray) -> float:
        """0: a push is an outside force, not a field with a potential."""
        return 0.0


class BodyAnchor:
    """Points of bodies held near world points by stiff damped springs (a ball joint by
    penalty): ``f = −k (p − a) − c ṗ`` at the body point ``p``, ``ṗ = v + ω × (p − x)``;
    ``U = ½ k |p − a|²``. A spinning top's tip on its pivot.

    Args:
        body: ``(K,)`` the body of each anchor.
        arm: ``(K, 3)`` the anchored point from the body's centre of mass, in its own axes [m].
        at: ``(K, 3)`` the world point it is held at [m].
        stiffness: ``(K,)`` k [N/m]. damping: ``(K,)`` c [N·s/m].
        mass: ``(B,)`` every body's mass [kg]; moments ``(B, 3)`` and axes ``(B, 4)``: its
            principal moments [kg·m²] and principal frame in its own axes (for ``ω``).
    """

    velocity_dependent = True
    #: No compiled form: a scene with it takes the generic road.
    compiled = None

    def __init__(self, body, arm, at, stiffness, damping, mass, moments, axes) -> None:  # type: ignore[no-untyped-def]
        self.body = np.asarray(body, dtype=np.int64)
        self.arm = np.asarray(arm, dtype=np.float64).reshape(-1, 3)
        self.at = np.asarray(at, dtype=np.float64).reshape(-1, 3)
        self.stiffness = np.asarray(stiffness, dtype=np.float64)[:, None]
        self.damping = np.asarray(damping, dtype=np.float64)[:, None]
        self.inverse_mass = 1.0 / np.asarray(mass, dtype=np.float64)[self.body, None]
        self.inverse_moments = 1.0 / np.asarray(moments, dtype=np.float64)[self.body]
        self.axes = np.asarray(axes, dtype=np.float64)[self.body]
        self.conservative = not self.damping.any()  # type: ignore[misc]

    def accumulate_wrench(self, t, x, q, momentum, angular_momentum, force, torque) -> None:  # type: ignore[no-untyped-def]
        """Add each anchor's spring and damper force at its point, and their torques."""
        body = self.body
        points = _world_points(q, body, x, self.arm)
        principal = quaternion_matrix(quaternion_multiply(q[body], self.axes))
        spin = np.einsum("kij,kj->ki", principal.transpose(0, 2, 1), angular_momentum[body])
        omega = np.einsum("kij,kj->ki", principal, spin * self.inverse_moments)
        velocity = momentum[body] * self.inverse_mass + np.cross(omega, points - x[body])
        pull = -self.stiffness * (points - self.at) - self.damping * velocity
        f, tau = wrench_at(x[body], points, pull)
        np.add.at(force, body, f)
        np.add.at(torque, body, tau)

    def potential(self, t: float, x: np.ndarray, q: np.ndarray) -> float:
        """``Σ ½ k |p − a|²`` [J]."""
        stretch = _world_points(q, self.body, x, self.arm) - self.at
        return float(0.5 * np.einsum("k,ki,ki->", self.stiffness[:, 0], stretch, stretch))
