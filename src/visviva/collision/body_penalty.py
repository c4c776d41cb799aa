"""Penalty contact between rigid bodies: springs that push overlapping bodies apart.

The alternative to impulses that seeds 000 and 002 describe ("temporary springs that oppose
inter-penetration"), for bodies as :mod:`~visviva.collision.penalty` does it for particles: no
time of impact is sought and nothing is projected; where two bodies' pieces (or a body and a
collider) overlap by ``d`` at a contact point of the manifold, with unit normal ``n`` from A
toward B and the relative velocity ``u`` of B's material point from A's there, B feels

    f_n = max(0, k d − c u·n)                       (never pulls)                [N]
    f_t = −min(μ f_n, c |u_t|) u_t / |u_t|,  u_t = u − (u·n) n   (Coulomb, viscous below it)
    F   = f_n n + f_t  at the point, and A the opposite;   U = ½ k d²  per point  [J]

with stiffness ``k`` [N/m] and damping ``c`` [N·s/m] per contact point. It is a force like any
other, evaluated at every stage of any integrator; the contacts are found anew at each
evaluation by the same detection as the impulses' (:class:`~visviva.collision.body_contacts.
BodyContacts`). A box resting on a face has four points, so it sinks ``M g / (4 k)``; the step
an explicit method can take is ``h < 2 √(m/k)`` for the lightest body ``m``.

References:
    Seeds 000 and 002 (penalty forces); M. Moore, J. Wilhelms, "Collision detection and
    response for computer animation", SIGGRAPH 1988.
"""

from __future__ import annotations

import numpy as np

from ..geometry.quaternions import quaternion_matrix
from .body_contacts import BodyContacts, bodies_of
from .body_response import body_frames

__all__ = ["BodyPenalty"]


class BodyPenalty:
    """The penalty contact force of a scene's rigid bodies (module docstring).

    Args:
        detector: The contact stage the scene would have had (its pieces, planes, meshes and
            pair rule); only its detection is used.
        stiffness: ``k`` [N/m] per contact point, > 0.
        damping: ``c`` [N·s/m] per contact point, ≥ 0.
    """

    velocity_dependent = True
    #: No compiled form: a scene with it takes the generic road.
    compiled = None

    def __init__(self, detector: BodyContacts, stiffness: float, damping: float) -> None:
        self.detector = detector
        self.stiffness = float(stiffness)
        self.damping = float(damping)
        self.conservative = self.damping == 0.0

    def _overlaps(self, x: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, ...]:
        """The overlapping contact points at centres of mass ``x`` and orientations ``q``:
        ``(body_a, body_b, point, normal, depth, friction)``, depth > 0."""
        detector = self.detector
        movers = detector.movers
        unit = q / np.linalg.norm(q, axis=1, keepdims=True)
        x = np.ascontiguousarray(x, dtype=np.float64)
        found, _, _ = detector.detect(movers, x, quaternion_matrix(unit), np.zeros(len(x)))
        piece_a, piece_b, point, normal, depth = found
        overlap = depth > 0.0
        piece_a, piece_b = piece_a[overlap], piece_b[overlap]
        body_a, body_b = bodies_of(movers, piece_a, piece_b)
        _, friction = detector.coefficients(movers.pieces, piece_a, piece_b)
        return body_a, body_b, point[overlap], normal[overlap], depth[overlap], friction

    def accumulate_wrench(self, t, x, q, momentum, angular_momentum, force, torque) -> None:  # type: ignore[no-untyped-def]
        """Add every overlapping contact's spring, damper and friction force at its point to
        both bodies, and their torques about the centres of mass."""
        body_a, body_b, point, normal, depth, mu = self._overlaps(x, q)
        if not depth.size:
            return
        movers = self.detector.movers
        _, _, v, w = body_frames(q / np.linalg.norm(q, axis=1, keepdims=True),
                                 movers.inverse_inertia, movers.inverse_mass,
                                 np.ascontiguousarray(momentum),
                                 np.ascontiguousarray(angular_momentum))  # fmt: skip
        world = body_a < 0
        a = np.maximum(body_a, 0)
        arm_a = np.where(world[:, None], 0.0, point - x[a])
        arm_b = point - x[body_b]
        moving_a = np.where(world[:, None], 0.0, v[a] + np.cross(w[a], arm_a))
        u = v[body_b] + np.cross(w[body_b], arm_b) - moving_a
        u_n = np.einsum("ci,ci->c", u, normal)
        push = np.maximum(self.stiffness * depth - self.damping * u_n, 0.0)
        sliding = u - u_n[:, None] * normal
        speed = np.linalg.norm(sliding, axis=1)
        drag = np.minimum(mu * push, self.damping * speed)
        with np.errstate(invalid="ignore", divide="ignore"):
            along = np.where(speed[:, None] > 0.0, sliding / speed[:, None], 0.0)
        f = push[:, None] * normal - drag[:, None] * along
        np.add.at(force, body_b, f)
        np.add.at(torque, body_b, np.cross(arm_b, f))
        np.add.at(force, a[~world], -f[~world])
        np.add.at(torque, a[~world], -np.cross(arm_a[~world], f[~world]))

    def potential(self, t: float, x: np.ndarray, q: np.ndarray) -> float:
        """``Σ ½ k d²`` [J] over the overlapping contact points."""
        depth = self._overlaps(x, q)[4]
        return float(0.5 * self.stiffness * (depth * depth).sum())
