"""Posed convex solids for the pair queries: capsule, cylinder, cone, ellipsoid, convex hull.

With :class:`~visviva.collision.shapes.Sphere` and :class:`~visviva.collision.shapes.Box` these
are the convex shapes :func:`visviva.collision.distance` and :func:`visviva.collision.contacts`
take. Each is a frozen dataclass validated when made; dimensions follow
:mod:`visviva.rigid.primitives` (a capsule's, cylinder's and cone's axis along its own +y), and
``orientation`` is the unit quaternion (w, x, y, z) that turns the shape's axes into the world's.
:func:`posed_shape` turns any of them into the tuple the Numba kernels take
(:mod:`~visviva.collision.convex`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial import ConvexHull as _Qhull
from scipy.spatial import QhullError

from .._validation import describe, real_number
from ..errors import ModelError
from ..geometry.quaternions import quaternion_matrix
from . import convex
from .shapes import Box, Sphere, numbers, unit_quaternion

__all__ = [
    "Capsule",
    "Cone",
    "ConvexHull",
    "ConvexShape",
    "Cylinder",
    "Ellipsoid",
    "hull_faces",
    "posed_shape",
]

IDENTITY = (1.0, 0.0, 0.0, 0.0)


def _posed(shape: str, center: Any, orientation: Any) -> tuple[tuple[float, ...], tuple]:
    return numbers("center", shape, center, 3, " [m]"), unit_quaternion(shape, orientation)


def _round_solid(solid: Any, place: str, shape: str, flat_height: bool) -> None:
    """Validate, in place, a round solid's ``place`` (its centre or base), ``orientation``,
    ``radius`` (> 0) and ``height`` (> 0, or ≥ 0 with ``flat_height``: a capsule of height
    zero is a sphere)."""
    where, q = _posed(shape, getattr(solid, place), solid.orientation)
    radius = real_number("radius", solid.radius, positive=True, unit=" m")
    height = real_number("height", solid.height, positive=not flat_height,
                         nonnegative=flat_height, unit=" m")  # fmt: skip
    for name, value in ((place, where), ("orientation", q), ("radius", radius), ("height", height)):
        object.__setattr__(solid, name, value)


@dataclass(frozen=True)
class Capsule:
    """A capsule: the points within ``radius`` of the segment of length ``height`` along its
    axis (total length ``height + 2·radius``; a height of zero is a sphere).

    Attributes:
        center: Centre [m], world frame.
        radius: Radius [m], > 0.
        height: Distance between the hemispheres' centres [m], ≥ 0.
        orientation: Unit quaternion (w, x, y, z); the identity puts the axis along +y.
    """

    center: tuple[float, float, float]
    radius: float
    height: float
    orientation: tuple[float, float, float, float] = IDENTITY

    def __post_init__(self) -> None:
        _round_solid(self, "center", "capsule", flat_height=True)


@dataclass(frozen=True)
class Cylinder:
    """A solid circular cylinder.

    Attributes:
        center: Centre [m], world frame.
        radius: Radius [m], > 0.
        height: Length along its axis [m], > 0.
        orientation: Unit quaternion (w, x, y, z); the identity puts the axis along +y.
    """

    center: tuple[float, float, float]
    radius: float
    height: float
    orientation: tuple[float, float, float, float] = IDENTITY

    def __post_init__(self) -> None:
        _round_solid(self, "center", "cylinder", flat_height=False)


@dataclass(frozen=True)
class Cone:
    """A solid right circular cone.

    Attributes:
        base: Centre of the base disc [m], world frame (the cone's own origin).
        radius: Base radius [m], > 0.
        height: From the base to the apex along its axis [m], > 0.
        orientation: Unit quaternion (w, x, y, z); the identity puts the apex above the base
            along +y.
    """

    base: tuple[float, float, float]
    radius: float
    height: float
    orientation: tuple[float, float, float, float] = IDENTITY

    def __post_init__(self) -> None:
        _round_solid(self, "base", "cone", flat_height=False)


@dataclass(frozen=True)
class Ellipsoid:
    """A solid ellipsoid.

    Attributes:
        center: Centre [m], world frame.
        semi_axes: Semi-axes along its own x, y, z [m], each > 0.
        orientation: Unit quaternion (w, x, y, z).
    """

    center: tuple[float, float, float]
    semi_axes: tuple[float, float, float]
    orientation: tuple[float, float, float, float] = IDENTITY

    def __post_init__(self) -> None:
        center, q = _posed("ellipsoid", self.center, self.orientation)
        axes = numbers("semi_axes", "ellipsoid", self.semi_axes, 3, " [m]")
        if not min(axes) > 0.0:
            raise ModelError(
                f"`semi_axes` of an ellipsoid must be three positive lengths [m] (got "
                f"{describe(axes)})"
            )
        object.__setattr__(self, "center", center)
        object.__setattr__(self, "orientation", q)
        object.__setattr__(self, "semi_axes", axes)


@dataclass(frozen=True, eq=False)
class ConvexHull:
    """The convex hull of points, placed by a position and an orientation.

    Attributes:
        points: ``(N, 3)`` points in the hull's own coordinates [m]; at least four not in one
            plane.
        position: Where the origin of the points' coordinates goes [m], world frame.
        orientation: Unit quaternion (w, x, y, z).
        vertices: ``(V, 3)`` the hull's corners, read-only (computed).
        planes: ``(F, 4)`` each face's outward unit normal and offset, ``n·x = d`` (computed).
        face_start: ``(F + 1,)`` and ``face_vertices``: each face's corners, counter-clockwise
            seen from outside (computed; :mod:`~visviva.collision.convex`).
    """

    points: np.ndarray
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    orientation: tuple[float, float, float, float] = IDENTITY
    vertices: np.ndarray = field(init=False, repr=False)
    planes: np.ndarray = field(init=False, repr=False)
    face_start: np.ndarray = field(init=False, repr=False)
    face_vertices: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "position", numbers("position", "convex hull", self.position, 3, " [m]")
        )
        object.__setattr__(self, "orientation", unit_quaternion("convex hull", self.orientation))
        vertices, planes, face_start, face_vertices = hull_faces(self.points)
        for name, array in (
            ("vertices", vertices),
            ("planes", planes),
            ("face_start", face_start),
            ("face_vertices", face_vertices),
        ):
            array.setflags(write=False)
            object.__setattr__(self, name, array)

    def __repr__(self) -> str:
        return f"ConvexHull({self.vertices.shape[0]} vertices, {self.planes.shape[0]} faces)"


ConvexShape = Sphere | Box | Capsule | Cylinder | Cone | Ellipsoid | ConvexHull


def hull_faces(points: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The convex hull of ``(N, 3)`` points as ``(vertices, planes, face_start,
    face_vertices)`` (:mod:`~visviva.collision.convex`): Qhull's triangles merged into
    polygons by their common plane, each polygon's corners counter-clockwise seen from
    outside. A ModelError for fewer than four points not in one plane, or non-finite ones."""
    try:
        array = np.array(points, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        array = None
    if array is None or array.ndim != 2 or array.shape[1] != 3 or array.shape[0] < 4:
        raise ModelError(
            f"`points` of a convex hull must be an (N, 3) array of N ≥ 4 points [m] "
            f"(got {describe(points)})"
        )
    if not np.isfinite(array).all():
        raise ModelError("`points` of a convex hull must be finite numbers [m]")
    try:
        qhull = _Qhull(array)
    except QhullError:
        raise ModelError(
            "`points` of a convex hull lie in one plane (or on one line): a hull needs volume; "
            "give points that span three dimensions"
        ) from None
    keep = qhull.vertices
    index = np.full(array.shape[0], -1, dtype=np.int64)
    index[keep] = np.arange(keep.size)
    vertices = array[keep]
    size = float(np.ptp(vertices, axis=0).max())
    # Qhull triangulates a merged facet into triangles of one plane: group them by it.
    planes: list[np.ndarray] = []
    groups: list[set[int]] = []
    for simplex, equation in zip(qhull.simplices, qhull.equations, strict=True):
        for k, plane in enumerate(planes):
            if (
                np.dot(plane[:3], equation[:3]) > 1.0 - 1e-10
                and abs(plane[3] - equation[3]) <= 1e-10 * size
            ):
                groups[k].update(int(index[v]) for v in simplex)
                break
        else:
            planes.append(equation)
            groups.append({int(index[v]) for v in simplex})
    face_start = [0]
    face_vertices: list[int] = []
    for plane, group in zip(planes, groups, strict=True):
        corners = np.array(sorted(group))
        normal = plane[:3]
        centre = vertices[corners].mean(axis=0)
        # An in-plane frame (u, w = n × u): angles in it grow counter-clockwise about n.
        u = vertices[corners[0]] - centre
        u /= np.linalg.norm(u)
        w = np.cross(normal, u)
        offsets = vertices[corners] - centre
        order = np.argsort(np.arctan2(offsets @ w, offsets @ u), kind="stable")
        face_vertices.extend(int(c) for c in corners[order])
        face_start.append(len(face_vertices))
    # Qhull's equations are n·x + offset = 0 with n outward: d = −offset.
    plane_array = np.array([[*p[:3], -p[3]] for p in planes])
    return (
        np.ascontiguousarray(vertices),
        plane_array,
        np.array(face_start, dtype=np.int64),
        np.array(face_vertices, dtype=np.int64),
    )


def posed_shape(shape: ConvexShape) -> tuple:
    """The tuple the kernels take: ``(kind, params, vertices, planes, face_start,
    face_vertices, position, rotation)`` (:mod:`~visviva.collision.convex`)."""
    empty = convex.empty_hull_arrays()
    if isinstance(shape, Sphere):
        return (convex.SPHERE, np.array([shape.radius, 0.0, 0.0, 0.0]), *empty,
                np.array(shape.center), np.eye(3))  # fmt: skip
    if isinstance(shape, ConvexHull):
        return (convex.HULL, np.zeros(4), shape.vertices, shape.planes, shape.face_start,
                shape.face_vertices, np.array(shape.position),
                quaternion_matrix(np.array(shape.orientation)))  # fmt: skip
    if isinstance(shape, Box):
        kind, params, origin = convex.BOX, [0.0, *shape.half_extents], shape.center
    elif isinstance(shape, Capsule):
        kind, params, origin = (
            convex.CAPSULE,
            [shape.radius, 0.5 * shape.height, 0.0, 0.0],
            shape.center,
        )
    elif isinstance(shape, Cylinder):
        kind, params, origin = (
            convex.CYLINDER,
            [0.0, shape.radius, 0.5 * shape.height, 0.0],
            shape.center,
        )
    elif isinstance(shape, Cone):
        kind, params, origin = convex.CONE, [0.0, shape.radius, shape.height, 0.0], shape.base
    elif isinstance(shape, Ellipsoid):
        kind, params, origin = convex.ELLIPSOID, [0.0, *shape.semi_axes], shape.center
    else:
        raise ModelError(
            f"expected a convex shape (Sphere, Box, Capsule, Cylinder, Cone, Ellipsoid or "
            f"ConvexHull from visviva.collision), got {describe(shape)}"
        )
    rotation = quaternion_matrix(np.array(shape.orientation))
    return (kind, np.array(params, dtype=np.float64), *empty, np.array(origin), rotation)
