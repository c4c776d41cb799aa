"""Collision geometry: static collider shapes and the Numba queries collision kernels call.

Particles (points with a radius) collide with static colliders. This package gives their
geometry and the two responses: the collision stage (impulses with restitution and friction,
time of impact by bisection; :mod:`~visviva.collision.response`) and the penalty force
(:mod:`~visviva.collision.penalty`). Particles also collide with each other as spheres
(:mod:`~visviva.collision.particle_contacts`).

* :mod:`~visviva.collision.shapes`: :class:`Plane` (half-space or slab), :class:`Sphere`,
  :class:`Box`, :class:`TriangleMesh`, validated at construction, each with vectorized
  ``signed_distance`` and ``first_hit``.
* :mod:`~visviva.collision.queries`: the scalar ``@njit`` distance and segment queries of the
  primitives; :mod:`~visviva.collision.tables`: the same over a table of colliders of a kind.
* :mod:`~visviva.collision.bvh`: a mesh's bounding-volume hierarchy as flat arrays, and its
  ``@njit`` closest-point, signed-distance and segment queries.

Sign and normal convention, shared by every shape: the distance is negative inside the solid,
and the normal is the outward unit normal at the closest surface point.

>>> import numpy as np
>>> floor = Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0))
>>> distance, normal = floor.signed_distance(np.array([[1.0, 0.25, 2.0]]))
>>> float(distance[0]), normal[0].tolist()
(0.25, [0.0, 1.0, 0.0])
>>> float(floor.first_hit([[0.0, 1.0, 0.0]], [[0.0, -3.0, 0.0]])[0])
0.25
"""

from __future__ import annotations

from .bvh import MeshBVH
from .colliders import MAX_COLLIDERS, ColliderSet
from .particle_contacts import PairContacts, ParticleContacts
from .penalty import PenaltyContact
from .proximity import ContactPatch, Separation, contacts, distance
from .response import ColliderResponse, ParticleCollisions
from .shapes import Box, Plane, Sphere, TriangleMesh
from .solids import Capsule, Cone, ConvexHull, Cylinder, Ellipsoid
from .tables import ColliderKind, collider_table

__all__ = [
    "MAX_COLLIDERS",
    "Box",
    "Capsule",
    "ColliderKind",
    "ColliderResponse",
    "ColliderSet",
    "Cone",
    "ContactPatch",
    "ConvexHull",
    "Cylinder",
    "Ellipsoid",
    "MeshBVH",
    "PairContacts",
    "ParticleCollisions",
    "ParticleContacts",
    "PenaltyContact",
    "Plane",
    "Separation",
    "Sphere",
    "TriangleMesh",
    "collider_table",
    "contacts",
    "distance",
]
