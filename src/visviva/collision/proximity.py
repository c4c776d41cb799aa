"""The pair queries of seed 003: ``distance(a, b)`` and ``contacts(a, b)`` on posed shapes.

Seed 003 builds collision handling on two queries: ``Distance(A, B)``, how far apart two
shapes are (or how deep they overlap), and ``Contacts(A, B)``, where they touch. Here they
take any two of the convex shapes (:class:`Sphere`, :class:`Box`, :class:`Capsule`,
:class:`Cylinder`, :class:`Cone`, :class:`Ellipsoid`, :class:`ConvexHull`) or a
:class:`Plane` and a convex shape, each placed in the world by its own position and
orientation. Convex pairs go through GJK, and EPA when they overlap
(:mod:`~visviva.collision.gjk`, :mod:`~visviva.collision.epa`); contacts clip the two
shapes' supporting faces (:mod:`~visviva.collision.manifold`).

One convention for both: the normal ``n`` is a unit vector from ``a`` toward ``b``, the
distance is negative when they overlap (minus the penetration depth), and moving ``b`` by
``−distance·n`` makes them just touch.

>>> from visviva.collision import Box, Sphere, distance, contacts
>>> table = Box(center=(0.0, 0.0, 0.0), size=(2.0, 0.2, 2.0))
>>> ball = Sphere(center=(0.3, 0.55, 0.0), radius=0.5)
>>> gap = distance(table, ball)
>>> round(gap.distance, 12), gap.normal.round(12).tolist()
(-0.05, [0.0, 1.0, 0.0])
>>> crate = Box(center=(0.0, 0.59, 0.0), size=(1.0, 1.0, 1.0))
>>> patch = contacts(table, crate)
>>> len(patch.points), patch.depths.round(12).tolist()
(4, [0.01, 0.01, 0.01, 0.01])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validation import real_number
from ..errors import ModelError
from .box_box import clip_work
from .manifold import CANDIDATES, plane_manifold
from .narrow_phase import convex_contacts
from .separation import plane_separation, shape_distance
from .shapes import Plane
from .solids import ConvexShape, posed_shape

__all__ = ["ContactPatch", "Separation", "contacts", "distance"]


@dataclass(frozen=True)
class Separation:
    """How far apart two shapes are.

    Attributes:
        distance: The gap [m] between them, negative when they overlap (minus the
            penetration depth).
        normal: ``(3,)`` unit vector from ``a`` toward ``b``: the direction in which ``b``
            moves away from ``a`` fastest (world frame).
        point_a: ``(3,)`` the point of ``a`` nearest ``b`` (deepest inside ``b`` if they
            overlap) [m].
        point_b: ``(3,)`` the same for ``b``; ``point_b − point_a = distance · normal``.
    """

    distance: float
    normal: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray


@dataclass(frozen=True)
class ContactPatch:
    """Where two shapes touch: up to four points sharing one normal.

    Attributes:
        normal: ``(3,)`` unit vector from ``a`` toward ``b`` (world frame).
        points: ``(k, 3)`` contact points [m], midway between the two surfaces; ``k = 0``
            when the shapes are farther apart than ``max_separation``.
        depths: ``(k,)`` penetration depth at each point [m], negative for a gap.
    """

    normal: np.ndarray
    points: np.ndarray
    depths: np.ndarray


def _pair(a: Any, b: Any) -> tuple[Any, tuple, bool]:
    """The first shape (a Plane's row, or a posed convex shape), the second posed, and whether
    the first is a plane."""
    if isinstance(b, Plane):
        raise ModelError(
            "a Plane must come first in a pair query: ask distance(plane, shape) (the normal "
            "then points from the plane toward the shape)"
        )
    if isinstance(a, Plane):
        return a, posed_shape(b), True
    return posed_shape(a), posed_shape(b), False


def _plane_arrays(plane: Plane) -> tuple[np.ndarray, np.ndarray, float]:
    return np.array(plane.point), np.array(plane.unit_normal), plane.thickness


def _separation(first: Any, second: tuple, is_plane: bool) -> tuple:
    if is_plane:
        return plane_separation(*_plane_arrays(first), second)
    return shape_distance(first, second)


def distance(a: Plane | ConvexShape, b: ConvexShape) -> Separation:
    """The signed distance between two posed shapes, with the normal and closest points.

    Args:
        a: A convex shape, or a :class:`Plane` (half-space or slab).
        b: A convex shape.

    Returns:
        A :class:`Separation` (the module docstring gives the convention). Exact for
        polytopes and round shapes (spheres, capsules) to rounding; for cylinders, cones,
        ellipsoids in contact within about 1e-7 of their size.
    """
    first, second, is_plane = _pair(a, b)
    d, nx, ny, nz, ax, ay, az, bx, by, bz = _separation(first, second, is_plane)
    return Separation(
        float(d), np.array([nx, ny, nz]), np.array([ax, ay, az]), np.array([bx, by, bz])
    )


def contacts(
    a: Plane | ConvexShape, b: ConvexShape, *, max_separation: float = 0.0
) -> ContactPatch:
    """Where two posed shapes touch: the contact manifold, up to four points.

    Args:
        a: A convex shape, or a :class:`Plane` (half-space or slab).
        b: A convex shape.
        max_separation: Also report points with a gap up to this [m], ≥ 0 (speculative
            contacts, which a solver uses to stop shapes before they meet).

    Returns:
        A :class:`ContactPatch`: the normal from ``a`` toward ``b``, and the points with their
        depths.
    """
    limit = real_number("max_separation", max_separation, nonnegative=True, unit=" m")
    first, second, is_plane = _pair(a, b)
    points = np.empty((CANDIDATES, 3))
    depths = np.empty(CANDIDATES)
    if is_plane:
        separation = _separation(first, second, is_plane)
        count, nx, ny, nz = plane_manifold(separation, second, limit, points, depths)
    else:
        count, nx, ny, nz = convex_contacts(first, second, limit, points, depths, clip_work())
    return ContactPatch(np.array([nx, ny, nz]), points[:count].copy(), depths[:count].copy())
