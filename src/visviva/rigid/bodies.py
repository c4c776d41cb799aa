"""A scene's rigid bodies as structure-of-arrays data: what they are and how they start.

:class:`RigidBodies` holds, per body, its mass properties (mass, principal moments, the
principal frame in the body's axes, the centre of mass in them), its damping rates, the shape
it is drawn with and its initial state ``(x, q, P, L)``: the centre of mass [m], the unit
quaternion of the body's axes (body to world), ``P = M v`` [kg·m/s] and ``L = I ω``
[kg·m²/s] in the world frame, ``I = R I_body Rᵀ``. :meth:`RigidBodies.motion` gives the
kinematics an integrator steps them with (:class:`~.motion.BodyMotion`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..geometry.quaternions import matrix_quaternion, quaternion_matrix
from .mass_properties import MassProperties
from .motion import BodyMotion

__all__ = ["DEFAULT_COLOR", "BodyStart", "BodyViews", "RigidBodies"]

#: The colour of a body that is given none: a light grey, sRGB (the scene entity's default).
DEFAULT_COLOR = (0.8, 0.8, 0.8)


@dataclass(frozen=True)
class BodyViews:
    """What the bodies' state ``(x, q, P, L)`` implies, every array's first axis the body
    (Baraff & Witkin's notes, §2): the velocity of the centre of mass ``v = P/M`` ``(B, 3)``
    [m/s], the rotation matrix ``R(q)`` ``(B, 3, 3)`` (body axes to world), the world inverse
    inertia ``I⁻¹ = R I_body⁻¹ Rᵀ`` ``(B, 3, 3)`` [1/(kg·m²)] and the angular velocity
    ``ω = I⁻¹ L`` ``(B, 3)`` [rad/s]: not conserved by a free body, whose ``L`` is."""

    velocity: np.ndarray
    rotation: np.ndarray
    inverse_inertia: np.ndarray
    angular_velocity: np.ndarray


@dataclass(frozen=True)
class BodyStart:
    """How one body starts: where its own origin is [m], its orientation (unit quaternion,
    body to world), the velocity of its centre of mass [m/s] and its angular velocity [rad/s]
    in the world frame."""

    position: np.ndarray
    orientation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray


@dataclass(frozen=True, eq=False)
class RigidBodies:
    """``B`` rigid bodies (see the module docstring); every array's first axis is the body.

    Attributes:
        names: Each body's name.
        mass: ``(B,)`` [kg].
        moments: ``(B, 3)`` principal moments of inertia [kg·m²], ascending.
        axes: ``(B, 4)`` the principal frame's orientation in the body's axes.
        center: ``(B, 3)`` the centre of mass in the body's axes [m].
        inertia: ``(B, 3, 3)`` the inertia about the centre of mass in the body's axes.
        linear_damping_rate: ``(B,)`` γ of ``P' = F − γ P`` [1/s].
        angular_damping_rate: ``(B,)`` γ of ``L' = τ − γ L`` [1/s].
        shapes: Each body's shape and dimensions, for drawing (``{"shape": ..., ...}``).
        color: ``(B, 3)`` the colour each body is drawn in, sRGB in [0, 1].
        position: ``(B, 3)`` initial centres of mass [m].
        orientation: ``(B, 4)`` initial orientations.
        momentum: ``(B, 3)`` initial ``P`` [kg·m/s].
        angular_momentum: ``(B, 3)`` initial ``L`` [kg·m²/s].
    """

    names: tuple[str, ...]
    mass: np.ndarray
    moments: np.ndarray
    axes: np.ndarray
    center: np.ndarray
    inertia: np.ndarray
    linear_damping_rate: np.ndarray
    angular_damping_rate: np.ndarray
    shapes: tuple[dict[str, Any], ...]
    color: np.ndarray
    position: np.ndarray
    orientation: np.ndarray
    momentum: np.ndarray
    angular_momentum: np.ndarray

    @classmethod
    def of(
        cls,
        names: Sequence[str],
        properties: Sequence[MassProperties],
        starts: Sequence[BodyStart],
        shapes: Sequence[dict[str, Any]],
        linear_damping_rate: Sequence[float],
        angular_damping_rate: Sequence[float],
        colors: Sequence[Sequence[float]] | None = None,
    ) -> RigidBodies:
        """The bodies with these mass properties (about the centre of mass, in each body's
        axes), starts, shapes, damping rates and colours (sRGB in [0, 1]; default
        :data:`DEFAULT_COLOR`)."""
        moments, axes, orientation, position, momentum, spin = [], [], [], [], [], []
        for mp, start in zip(properties, starts, strict=True):
            principal, frame = mp.principal()
            q = np.asarray(start.orientation, dtype=np.float64)
            q = q / np.linalg.norm(q)
            rotation = quaternion_matrix(q)
            world_inertia = rotation @ np.asarray(mp.inertia) @ rotation.T
            moments.append(principal)
            axes.append(matrix_quaternion(frame))
            orientation.append(q)
            position.append(np.asarray(start.position) + rotation @ np.asarray(mp.center_of_mass))
            momentum.append(mp.mass * np.asarray(start.velocity, dtype=np.float64))
            spin.append(world_inertia @ np.asarray(start.angular_velocity, dtype=np.float64))
        count = len(properties)

        def stacked(rows: list[np.ndarray], width: int) -> np.ndarray:
            return np.array(rows, dtype=np.float64).reshape(count, width)

        return cls(
            names=tuple(names),
            mass=np.array([mp.mass for mp in properties], dtype=np.float64),
            moments=stacked(moments, 3),
            axes=stacked(axes, 4),
            center=stacked([np.asarray(mp.center_of_mass) for mp in properties], 3),
            inertia=np.array([mp.inertia for mp in properties], dtype=np.float64).reshape(-1, 3, 3),
            linear_damping_rate=np.array(linear_damping_rate, dtype=np.float64),
            angular_damping_rate=np.array(angular_damping_rate, dtype=np.float64),
            shapes=tuple(shapes),
            color=stacked(
                [np.asarray(c) for c in colors] if colors is not None else [DEFAULT_COLOR] * count,
                3,
            ),
            position=stacked(position, 3),
            orientation=stacked(orientation, 4),
            momentum=stacked(momentum, 3),
            angular_momentum=stacked(spin, 3),
        )

    @property
    def count(self) -> int:
        return int(self.mass.shape[0])

    def views(
        self, orientation: np.ndarray, momentum: np.ndarray, angular_momentum: np.ndarray
    ) -> BodyViews:
        """The derived quantities of the bodies' state (orientations ``(B, 4)``, momenta and
        angular momenta ``(B, 3)``, world frame): see :class:`BodyViews`."""
        q = np.asarray(orientation, dtype=np.float64)
        rotation = quaternion_matrix(q / np.linalg.norm(q, axis=1, keepdims=True))
        # The inertia is I_body in the body's axes: I⁻¹ = R I_body⁻¹ Rᵀ.
        inverse = rotation @ np.linalg.inv(self.inertia) @ rotation.transpose(0, 2, 1)
        return BodyViews(
            velocity=np.asarray(momentum) / self.mass[:, None],
            rotation=rotation,
            inverse_inertia=inverse,
            angular_velocity=np.einsum("bij,bj->bi", inverse, angular_momentum),
        )

    def motion(self, offset: int) -> BodyMotion:
        """The bodies' kinematics after ``offset`` entries that move as ``q' = v``."""
        return BodyMotion(offset, self.mass, self.moments, self.axes)

    def positions(self) -> np.ndarray:
        """The initial ``q`` entries of the bodies: ``x`` (3B), then ``q`` (4B)."""
        return np.concatenate([self.position.ravel(), self.orientation.ravel()])

    def momenta(self) -> np.ndarray:
        """The initial ``v`` entries of the bodies: ``P`` (3B), then ``L`` (3B)."""
        return np.concatenate([self.momentum.ravel(), self.angular_momentum.ravel()])
