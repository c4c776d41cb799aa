"""What moves in a step's rigid contacts: the bodies, and the particles that meet them.

The contact stage of rigid bodies (:mod:`~visviva.collision.body_contacts`) works on *movers*:
each has a mass, an inertia and convex pieces. The bodies are movers of their own; a particle
that meets the bodies (a ball poured onto a tumbling box) joins a step as one more mover: a
sphere of its radius, of its mass, that does not turn (its inertia is infinite, as a particle
has no spin). A particle's contacts with other particles and with the colliders are its own
stages' (:mod:`~visviva.collision.particle_contacts`, :mod:`~visviva.collision.response`);
here it meets the bodies' pieces only.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .body_pieces import BodyPieces
from .convex import SPHERE

__all__ = ["Movers"]


@dataclass(frozen=True, eq=False)
class Movers:
    """``M`` movers and their pieces; every per-mover array's first axis is the mover.

    Attributes:
        pieces: Their convex pieces (and the static scenery's, of mover -1).
        inverse_mass: ``(M,)`` [1/kg], 0 for a mover nothing pushes.
        inverse_inertia: ``(M, 3, 3)`` in each mover's axes [1/(kg·m²)], 0 for one that
            does not turn.
        inertia: ``(M, 3, 3)`` in each mover's axes [kg·m²] (unused where it does not turn).
        dynamic: ``(M,)`` bool: pushed by contacts.
        size: ``(M,)`` the farthest any of its pieces reaches from its centre of mass [m].
        particle: ``(P,)`` bool per piece: a particle's sphere, which meets only the bodies'
            pieces.
        bodies: How many of the movers are bodies (the particles follow them).
    """

    pieces: BodyPieces
    inverse_mass: np.ndarray
    inverse_inertia: np.ndarray
    inertia: np.ndarray
    dynamic: np.ndarray
    size: np.ndarray
    particle: np.ndarray
    bodies: int

    @property
    def count(self) -> int:
        return int(self.inverse_mass.shape[0])

    @property
    def reach(self) -> np.ndarray:
        """``(P,)`` each piece's farthest point from its mover's centre of mass [m]."""
        return np.linalg.norm(self.pieces.local_position, axis=1) + self.pieces.radius

    @classmethod
    def of_bodies(
        cls, pieces: BodyPieces, mass: np.ndarray, inertia: np.ndarray, dynamic: np.ndarray
    ) -> Movers:
        """The bodies as movers: ``mass`` ``(B,)`` [kg], ``inertia`` ``(B, 3, 3)`` about the
        centre of mass in each body's axes [kg·m²], ``dynamic`` ``(B,)``."""
        dynamic = np.asarray(dynamic, dtype=np.bool_)
        inertia = np.asarray(inertia, dtype=np.float64)
        count = dynamic.shape[0]
        size = np.zeros(count)
        reach = np.linalg.norm(pieces.local_position, axis=1) + pieces.radius
        owned = pieces.body >= 0
        np.maximum.at(size, pieces.body[owned], reach[owned])
        return cls(
            pieces=pieces,
            inverse_mass=np.where(dynamic, 1.0 / np.asarray(mass, dtype=np.float64), 0.0),
            inverse_inertia=np.where(dynamic[:, None, None], np.linalg.inv(inertia), 0.0),
            inertia=inertia,
            dynamic=dynamic,
            size=size,
            particle=np.zeros(pieces.count, dtype=np.bool_),
            bodies=count,
        )

    def with_particles(
        self, radius: np.ndarray, inverse_mass: np.ndarray, restitution: float, friction: float
    ) -> Movers:
        """These movers and ``K`` particles after them: spheres of ``radius`` ``(K,)`` [m] and
        ``inverse_mass`` ``(K,)`` [1/kg] (0: held still), turning never, with one
        ``restitution`` and ``friction`` for their contacts."""
        k = radius.shape[0]
        pieces = self.pieces
        first = self.count
        spheres = replace(
            pieces,
            body=np.concatenate([pieces.body, np.arange(first, first + k, dtype=np.int64)]),
            kind=np.concatenate([pieces.kind, np.full(k, SPHERE, dtype=np.int64)]),
            params=np.concatenate([pieces.params, np.column_stack([radius, np.zeros((k, 3))])]),
            local_position=np.concatenate([pieces.local_position, np.zeros((k, 3))]),
            local_rotation=np.concatenate([pieces.local_rotation, np.tile(np.eye(3), (k, 1, 1))]),
            radius=np.concatenate([pieces.radius, radius]),
            restitution=np.concatenate([pieces.restitution, np.full(k, restitution)]),
            friction=np.concatenate([pieces.friction, np.full(k, friction)]),
            vertex_start=_extend(pieces.vertex_start, k),
            plane_start=_extend(pieces.plane_start, k),
            face_start_start=_extend(pieces.face_start_start, k),
            face_vertex_start=_extend(pieces.face_vertex_start, k),
        )
        zeros = np.zeros((k, 3, 3))
        return Movers(
            pieces=spheres,
            inverse_mass=np.concatenate([self.inverse_mass, inverse_mass]),
            inverse_inertia=np.concatenate([self.inverse_inertia, zeros]),
            inertia=np.concatenate([self.inertia, zeros]),
            dynamic=np.concatenate([self.dynamic, inverse_mass > 0.0]),
            size=np.concatenate([self.size, radius]),
            particle=np.concatenate([self.particle, np.ones(k, dtype=np.bool_)]),
            bodies=self.bodies,
        )


def _extend(starts: np.ndarray, k: int) -> np.ndarray:
    """Pooled offsets with ``k`` more pieces that hold nothing in the pool."""
    return np.concatenate([starts, np.full(k, starts[-1], dtype=np.int64)])
