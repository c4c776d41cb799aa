"""Static collider shapes: plane slab, sphere, oriented box and closed triangle mesh.

Each shape is a frozen dataclass, validated when it is made (a :class:`~visviva.errors.ModelError`
names the field, the value and the fix) and never changed afterwards. SI units: lengths in
metres, world frame, Y up; orientations are unit quaternions (w, x, y, z). Every shape answers
two vectorized queries with one convention (see :mod:`visviva.collision.queries`):

* ``signed_distance(points) -> (distance, normal)``: ``distance`` ``(N,)`` [m] from each point
  to the surface, negative inside the solid, and the outward unit ``normal`` ``(N, 3)`` at the
  closest surface point, so that ``points − distance·normal`` lies on the surface.
* ``first_hit(start, end) -> fraction``: per segment, the smallest ``s`` in [0, 1] with
  ``start + s (end − start)`` in the solid; 0 for a start inside, ``inf`` for a miss.

Collision kernels use the same queries in Numba form: the primitives through their table rows
(:meth:`Plane.table_row`, :func:`visviva.collision.tables.collider_table`), a mesh through its
:attr:`TriangleMesh.bvh` arrays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from .._validation import describe, real_number
from ..errors import ModelError
from ..geometry.mesh_topology import check_closed_mesh, enclosed_volume, pseudo_normals
from .bvh import MeshBVH, mesh_closest_points, mesh_distances, mesh_first_hits
from .tables import ColliderKind, check_points, collider_distances, collider_first_hits

__all__ = ["QUATERNION_TOLERANCE", "Box", "Plane", "Sphere", "TriangleMesh"]

#: Largest accepted | |q| − 1 | of a box orientation: a quaternion further from unit length is a
#: mistake (a rotation composed without renormalizing, or not a rotation at all), not rounding.
QUATERNION_TOLERANCE = 1e-6

Vector3 = tuple[float, float, float]


def numbers(name: str, shape: str, value: Any, count: int, unit: str) -> tuple[float, ...]:
    """``value`` as ``count`` finite floats, or a ModelError naming ``name`` of a ``shape``."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        array = None
    if array is None or array.shape != (count,) or not np.isfinite(array).all():
        raise ModelError(
            f"`{name}` of a {shape} must be {count} finite numbers{unit} (got {describe(value)})"
        )
    return tuple(float(x) for x in array)


def unit_quaternion(shape: str, value: Any) -> tuple[float, float, float, float]:
    """``value`` as the unit quaternion (w, x, y, z) of a ``shape``'s ``orientation``, or a
    ModelError."""
    q = numbers("orientation", shape, value, 4, ", a quaternion (w, x, y, z)")
    norm = math.sqrt(sum(x * x for x in q))
    if norm == 0.0:
        raise ModelError(
            f"`orientation` of a {shape} must be a unit quaternion (w, x, y, z) (got "
            f"{describe(q)}); use (1, 0, 0, 0) for a {shape} aligned with the world axes"
        )
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise ModelError(
            f"`orientation` of a {shape} must be a unit quaternion (w, x, y, z) (got "
            f"{describe(q)}, of length {norm:.9g}); normalize it: divide it by its length"
        )
    return q  # type: ignore[return-value]


class _Primitive:
    """The vectorized queries of a shape with a table row."""

    kind: ClassVar[ColliderKind]

    def table_row(self) -> np.ndarray:
        """The shape's row of its kind's collider table (:mod:`visviva.collision.tables`)."""
        raise NotImplementedError

    def signed_distance(self, points: Any) -> tuple[np.ndarray, np.ndarray]:
        """Signed distance ``(N,)`` [m] and outward unit normal ``(N, 3)`` of ``(N, 3)`` points."""
        distance, normal, _ = collider_distances(self.kind, self.table_row()[None, :], points)
        return distance, normal

    def first_hit(self, start: Any, end: Any) -> np.ndarray:
        """Fraction ``(N,)`` at which each segment ``start → end`` (``(N, 3)`` each) enters."""
        fraction, _ = collider_first_hits(self.kind, self.table_row()[None, :], start, end)
        return fraction


@dataclass(frozen=True)
class Plane(_Primitive):
    """A plane slab: the points whose height ``s = (x − point)·n̂`` lies in [−thickness, 0].

    ``n̂`` is ``normal`` made unit length; it points out of the solid, so ``point`` lies on the
    slab's outer face. An infinite thickness (the default) makes a half-space: a floor with
    ``normal=(0, 1, 0)``. A finite thickness makes a wall that a fast particle can cross in one
    step; :meth:`first_hit` still sees the crossing.

    Attributes:
        point: A point of the outer face [m], world frame.
        normal: Outward normal direction, any nonzero length (world frame).
        thickness: Depth of the solid below the outer face [m], > 0; ``math.inf`` for a
            half-space.
    """

    point: Vector3
    normal: Vector3
    thickness: float = math.inf
    kind: ClassVar[ColliderKind] = ColliderKind.PLANE

    def __post_init__(self) -> None:
        point = numbers("point", "plane", self.point, 3, " [m]")
        normal = numbers("normal", "plane", self.normal, 3, "")
        if not math.hypot(*normal) > 0.0:
            raise ModelError(
                f"`normal` of a plane must not be zero (got {describe(normal)}); give the "
                "direction pointing out of the solid, e.g. (0, 1, 0) for a floor"
            )
        thickness = self.thickness
        if not (isinstance(thickness, (float, np.floating)) and thickness == math.inf):
            thickness = real_number("thickness", thickness, positive=True, unit=" m")
        object.__setattr__(self, "point", point)
        object.__setattr__(self, "normal", normal)
        object.__setattr__(self, "thickness", float(thickness))

    @property
    def unit_normal(self) -> Vector3:
        """``normal`` scaled to unit length."""
        length = math.hypot(*self.normal)
        return (self.normal[0] / length, self.normal[1] / length, self.normal[2] / length)

    def table_row(self) -> np.ndarray:
        """``[point (3), unit normal (3), thickness]``, shape ``(7,)``."""
        return np.array([*self.point, *self.unit_normal, self.thickness])


@dataclass(frozen=True)
class Sphere(_Primitive):
    """A solid ball.

    Attributes:
        center: Centre [m], world frame.
        radius: Radius [m], > 0.
    """

    center: Vector3
    radius: float
    kind: ClassVar[ColliderKind] = ColliderKind.SPHERE

    def __post_init__(self) -> None:
        center = numbers("center", "sphere", self.center, 3, " [m]")
        radius = real_number("radius", self.radius, positive=True, unit=" m")
        object.__setattr__(self, "center", center)
        object.__setattr__(self, "radius", radius)

    def table_row(self) -> np.ndarray:
        """``[center (3), radius]``, shape ``(4,)``."""
        return np.array([*self.center, self.radius])


@dataclass(frozen=True)
class Box(_Primitive):
    """A solid oriented box.

    Attributes:
        center: Centre [m], world frame.
        size: Full edge lengths along the box's own x, y, z axes [m], each > 0.
        orientation: Unit quaternion (w, x, y, z) rotating the box's axes into the world
            frame; ``(1, 0, 0, 0)``, the default, aligns them with the world axes.
    """

    center: Vector3
    size: Vector3
    orientation: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    kind: ClassVar[ColliderKind] = ColliderKind.BOX

    def __post_init__(self) -> None:
        center = numbers("center", "box", self.center, 3, " [m]")
        size = numbers("size", "box", self.size, 3, " [m]")
        if not min(size) > 0.0:
            raise ModelError(
                f"`size` of a box must be three positive edge lengths [m] (got {describe(size)}); "
                "it is the full length of each edge, twice the half extent"
            )
        q = unit_quaternion("box", self.orientation)
        object.__setattr__(self, "center", center)
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "orientation", q)

    @property
    def half_extents(self) -> Vector3:
        """Half the edge lengths [m]."""
        return (0.5 * self.size[0], 0.5 * self.size[1], 0.5 * self.size[2])

    def table_row(self) -> np.ndarray:
        """``[center (3), half extents (3), quaternion (w, x, y, z)]``, shape ``(10,)``.

        The quaternion is divided by its length (within :data:`QUATERNION_TOLERANCE` of 1), so
        the kernels rotate without scaling.
        """
        q = np.array(self.orientation)
        return np.concatenate([self.center, self.half_extents, q / np.linalg.norm(q)])


@dataclass(frozen=True, eq=False)
class TriangleMesh:
    """A closed solid bounded by triangles.

    The mesh must be watertight (every edge shared by exactly two triangles), consistently
    oriented, and counter-clockwise seen from outside (positive enclosed volume); see
    :func:`visviva.geometry.mesh_topology.check_closed_mesh` for every check. Queries walk a
    bounding-volume hierarchy built once here (:class:`visviva.collision.bvh.MeshBVH`).

    Attributes:
        vertices: ``(V, 3)`` vertex positions [m], world frame (a read-only float64 copy).
        triangles: ``(T, 3)`` vertex indices per triangle (a read-only int64 copy).
        bvh: The hierarchy and pseudo-normals, for Numba kernels (see
            :mod:`visviva.collision.bvh`).
    """

    vertices: np.ndarray
    triangles: np.ndarray
    bvh: MeshBVH = field(init=False, repr=False)

    def __post_init__(self) -> None:
        vertices, triangles, triangle_edges = check_closed_mesh(self.vertices, self.triangles)
        normals = pseudo_normals(vertices, triangles, triangle_edges)
        vertices.setflags(write=False)
        triangles.setflags(write=False)
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "triangles", triangles)
        object.__setattr__(self, "bvh", MeshBVH.build(vertices, triangles, normals))

    def __repr__(self) -> str:
        return (
            f"TriangleMesh({self.vertices.shape[0]} vertices, {self.triangles.shape[0]} triangles)"
        )

    @property
    def volume(self) -> float:
        """Enclosed volume [m³]."""
        return enclosed_volume(self.vertices, self.triangles)

    def signed_distance(self, points: Any) -> tuple[np.ndarray, np.ndarray]:
        """Signed distance ``(N,)`` [m] and outward unit normal ``(N, 3)`` of ``(N, 3)`` points."""
        return mesh_distances(self.bvh, check_points("points", points))

    def first_hit(self, start: Any, end: Any) -> np.ndarray:
        """Fraction ``(N,)`` at which each segment ``start → end`` (``(N, 3)`` each) enters."""
        start = check_points("start", start)
        end = check_points("end", end)
        if start.shape != end.shape:
            raise ModelError(
                f"`start` and `end` must have the same shape (got {start.shape} and {end.shape})"
            )
        return mesh_first_hits(self.bvh, start, end)

    def closest_point(self, points: Any) -> tuple[np.ndarray, np.ndarray]:
        """Closest surface point ``(N, 3)`` [m] to each of ``(N, 3)`` points, and the index of
        the triangle holding it ``(N,)``."""
        return mesh_closest_points(self.bvh, check_points("points", points))
