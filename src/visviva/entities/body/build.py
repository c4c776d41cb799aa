"""How ``body`` entities are built: the scene's rigid bodies, their mass properties, starts and
forces, and the projection stage that keeps their orientations unit quaternions.

Each body's mass properties come from its shape (:func:`visviva.rigid.mass_properties`: closed
forms for the primitives, Mirtich's integrals for a mesh, which must be a closed, outward,
non-self-intersecting surface); a body given a ``mass`` has the density that gives it. A
refusal names the entity and its field. The bodies feel the world's gravity and their own
damping (:mod:`visviva.forces.body_forces`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...errors import ModelError
from ...forces.body_forces import BodyAnchor, BodyDamping, BodyForce, BodyGravity, BodyPush
from ...geometry.quaternions import quaternion_matrix
from ...rigid.bodies import BodyStart, RigidBodies
from ...rigid.mass_properties import MassProperties
from ...rigid.projection import BodyProjection
from ...rigid.shapes import mass_properties
from ..context import BuildContext, Located
from ..kind import KindBuild
from ..mesh_files import with_mesh_file
from .schema import DIMENSIONS, Anchor, Push, RigidBody

__all__ = ["BUILD"]


def _finish(entries: Sequence[tuple[str, RigidBody]], context: BuildContext) -> None:
    """The scene's rigid bodies, the forces on them and their projection stage.

    Raises:
        Located: At the entity and field of a body whose shape no mass properties can be
            computed for (a mesh that is open, inside-out or crosses itself, a degenerate
            triangle, dimensions beyond what a float holds).
    """
    chosen = list(entries)
    properties, starts, shapes = [], [], []
    for where, entity in chosen:
        properties.append(_driven(entity, _mass_properties(where, entity)))
        starts.append(_start(where, entity))
        shapes.append({"shape": entity.shape, **_shape(entity)})
    with np.errstate(over="ignore"):  # a weight beyond the float range diverges, named
        bodies, forces = _bodies(chosen, properties, starts, shapes, context)
    context.bodies = bodies
    context.body_forces += forces
    context.stages.append(BodyProjection(bodies.count))


def _bodies(
    chosen: list[tuple[str, RigidBody]],
    properties: list[MassProperties],
    starts: list[BodyStart],
    shapes: list[dict[str, Any]],
    context: BuildContext,
) -> tuple[RigidBodies, list[BodyForce]]:
    bodies = RigidBodies.of(
        [context.names[context.index(where)] for where, _ in chosen],
        properties,
        starts,
        shapes,
        [e.linear_damping_rate if e.motion == "dynamic" else 0.0 for _, e in chosen],
        [e.angular_damping_rate if e.motion == "dynamic" else 0.0 for _, e in chosen],
        [e.color for _, e in chosen],
    )
    # Forces move dynamic bodies only: the others move as they are given.
    dynamic = np.array([e.motion == "dynamic" for _, e in chosen])
    forces: list[BodyForce] = []
    if context.gravity.any() and dynamic.any():
        forces.append(BodyGravity(context.scene.world.gravity, np.where(dynamic, bodies.mass, 0.0)))
    if bodies.linear_damping_rate.any() or bodies.angular_damping_rate.any():
        forces.append(BodyDamping(bodies.linear_damping_rate, bodies.angular_damping_rate))
    pushes = [(b, p) for b, (_, e) in enumerate(chosen) for p in e.push]
    if pushes:
        forces.append(_pushes(pushes, bodies))
    anchors = [(b, e.anchor) for b, (_, e) in enumerate(chosen) if e.anchor is not None]
    if anchors:
        forces.append(_anchors(anchors, bodies))
    return bodies, forces


def _arm(point: Any, bodies: RigidBodies, body: int) -> np.ndarray:
    """A point given in a body's own axes, from its centre of mass (the centre itself for
    ``None``)."""
    return np.zeros(3) if point is None else np.asarray(point) - bodies.center[body]


def _pushes(pushes: list[tuple[int, Push]], bodies: RigidBodies) -> BodyPush:
    """The pushes: a body point as its arm from the centre of mass, a world point as it is
    (the body's centre of mass at the start if none is given)."""
    arms = [
        (bodies.position[b] if p.point is None else np.asarray(p.point))
        if p.frame == "world"
        else _arm(p.point, bodies, b)
        for b, p in pushes
    ]
    return BodyPush(
        [b for b, _ in pushes],
        [p.force for _, p in pushes],
        arms,
        [p.start for _, p in pushes],
        [np.inf if p.duration is None else p.start + p.duration for _, p in pushes],
        [p.frame == "world" for _, p in pushes],
    )


def _anchors(anchors: list[tuple[int, Anchor]], bodies: RigidBodies) -> BodyAnchor:
    arms = [_arm(a.point, bodies, b) for b, a in anchors]
    rotations = quaternion_matrix(bodies.orientation[[b for b, _ in anchors]])
    starts = bodies.position[[b for b, _ in anchors]] + np.einsum("kij,kj->ki", rotations, arms)
    return BodyAnchor(
        [b for b, _ in anchors],
        arms,
        [start if a.at is None else a.at for start, (_, a) in zip(starts, anchors, strict=True)],
        [a.stiffness for _, a in anchors],
        [a.damping for _, a in anchors],
        bodies.mass,
        bodies.moments,
        bodies.axes,
    )


def _mass_properties(where: str, entity: RigidBody) -> Any:
    """The body's mass properties, with the density its ``mass`` asks for if it gives one."""
    try:
        with np.errstate(all="ignore"):
            properties = mass_properties(entity.shape, entity.density or 1.0, **_shape(entity))
            if entity.mass is not None:  # the same body at the density that gives that mass
                scale = entity.mass / properties.mass
                properties = MassProperties(
                    entity.mass, properties.center_of_mass, properties.inertia * scale,
                    properties.volume,
                )  # fmt: skip
    except ModelError as error:
        field = "vertices" if entity.shape == "mesh" else DIMENSIONS[entity.shape][0]
        raise Located(f"{where}.{field}", str(error)) from None
    return properties


def _driven(entity: RigidBody, properties: MassProperties) -> MassProperties:
    """A kinematic or static body's properties with its inertia made isotropic (the mean of
    its principal moments): nothing turns it, and with ``L = Ī ω`` it turns at the constant
    ``ω`` it is given, about a fixed axis, as a kinematic body must."""
    if entity.motion == "dynamic":
        return properties
    mean = float(np.trace(properties.inertia)) / 3.0
    return MassProperties(
        properties.mass, properties.center_of_mass, mean * np.eye(3), properties.volume
    )


def _shape(entity: RigidBody) -> dict[str, Any]:
    """The keywords of :func:`mass_properties` for the entity's shape (what drawing it needs
    too): its dimensions, or its mesh's arrays."""
    if entity.shape == "mesh":
        return {"vertices": np.array(entity.vertices), "triangles": np.array(entity.triangles)}
    return entity.dimensions()


def _start(where: str, entity: RigidBody) -> BodyStart:
    """How the body starts; a non-unit orientation is normalized, with a warning."""
    q = np.asarray(entity.orientation, dtype=np.float64)
    norm = math.hypot(*q)  # no overflow for components near the float limit
    if not np.isfinite(norm) or norm == 0.0:
        raise Located(
            f"{where}.orientation",
            "the orientation's length is not a finite positive number: give a unit quaternion",
        )
    if abs(norm - 1.0) > 1e-6:
        warnings.warn(
            f"{where}.orientation {tuple(entity.orientation)} has length {norm:.6g}, "
            "not 1: it is normalized (a rotation is a unit quaternion)",
            stacklevel=2,
        )
    return BodyStart(
        np.asarray(entity.position, dtype=np.float64),
        q / norm,
        np.asarray(entity.velocity, dtype=np.float64),
        np.asarray(entity.angular_velocity, dtype=np.float64),
    )


def _prepare(entity: RigidBody, where: str) -> RigidBody:
    """The body with its mesh file read (a body's mesh is checked as a solid when the scene is
    built)."""
    prepared: RigidBody = with_mesh_file(entity, where)
    return prepared


BUILD = KindBuild(prepare=_prepare, finish=_finish)
