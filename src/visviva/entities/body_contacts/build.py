"""How a ``body_contacts`` entity is built: each targeted body's convex pieces, the impulse
colliders as static pieces and planes, and the contact stage
(:class:`~visviva.collision.body_contacts.BodyContacts`). A scene holds at most one.

A body collides as its shape, centred where its mass properties put its centre of mass: a
primitive as itself, a mesh as its own surface only if that is convex (the hull of a
non-convex mesh is never taken silently: ``collision_shape = "hull"`` asks for it,
``"decomposition"`` cuts the mesh into convex pieces (:mod:`visviva.collision.decomposition`),
``convex_pieces`` gives them). The impulse colliders — planes, boxes, spheres and meshes
(met from outside) — act on every targeted body, with their own restitution and friction;
their ``targets`` choose particles only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.spatial import ConvexHull as Qhull

from ..._registry import did_you_mean
from ...collision import Box, Capsule, Cone, ConvexHull, Cylinder, Ellipsoid, Plane, Sphere
from ...collision.body_contacts import BodyContacts, ParticleMembers, Planes
from ...collision.body_penalty import BodyPenalty
from ...collision.body_pieces import BodyPieces
from ...collision.decomposition import convex_decomposition
from ...errors import ModelError, SceneProblem
from ...geometry.mesh_topology import enclosed_volume
from ..checks import check_names
from ..collider.shapes import collider_shape
from ..context import BuildContext, Located
from ..kind import KindBuild
from .schema import BodyContactSettings

__all__ = ["BUILD"]

#: A mesh is convex when its volume is its hull's to this relative tolerance.
CONVEX_TOLERANCE = 1e-9


def _check(entity: BodyContactSettings, where: str, scene: Any) -> list[SceneProblem]:
    """Targets that name body entities, and no other ``body_contacts`` entity before this one
    (two would disagree about the pairs they share)."""
    bodies = [e.name for e in scene.entities if e.type == "body" and e.name]
    problems = [
        SceneProblem(
            f"{where}.targets[{k}]",
            f"no body is called {name!r}.{did_you_mean(name, bodies)} Bodies: "
            f"{', '.join(bodies) or 'none named'}",
        )
        for k, name in enumerate(entity.targets or ())
        if name not in bodies
    ]
    problems += check_names(entity.particles, where, scene, field="particles")
    if entity.response == "penalty":
        if entity.stiffness is None:
            problems.append(SceneProblem(
                f"{where}.stiffness",
                'response = "penalty" needs `stiffness`, k per contact point [N/m]: a body '
                "of mass m sinks m g / k on one point and rings at √(k/m) rad/s",
            ))  # fmt: skip
        if entity.particles is not None:
            problems.append(SceneProblem(
                f"{where}.particles",
                'particles meet bodies by impulses only: drop `particles` or use response = '
                '"impulses"',
            ))  # fmt: skip
    first = next(i for i, e in enumerate(scene.entities) if e.type == "body_contacts")
    if f"entities[{first}]" != where:
        problems.append(
            SceneProblem(
                where,
                f"a scene holds at most one body_contacts entity; entities[{first}] is one "
                "already: merge their `targets` into it",
            )
        )
    return problems


def _finish(entries: Sequence[tuple[str, BodyContactSettings]], context: BuildContext) -> None:
    where, entity = entries[0]
    bodies = context.bodies
    if bodies is None:
        raise Located(where, "body contacts need rigid bodies: add a `body` entity")
    chosen = context.of_kind("body")
    wanted = None if entity.targets is None else set(entity.targets)
    shapes: list[Any] = []
    owner: list[int] = []
    restitution: list[float] = []
    friction: list[float] = []
    for b, (body_where, body) in enumerate(chosen):
        if wanted is not None and bodies.names[b] not in wanted:
            continue
        pieces = _pieces(body_where, body, -bodies.center[b])
        shapes += pieces
        owner += [b] * len(pieces)
        restitution += [body.restitution] * len(pieces)
        friction += [body.friction] * len(pieces)
    planes: list[tuple[Plane, float, float]] = []
    meshes: list[tuple[Any, float, float]] = []
    for collider_where, collider in context.of_kind("collider"):
        if collider.response != "impulse":
            continue
        shape = collider_shape(collider, collider_where)
        if isinstance(shape, Plane):
            planes.append((shape, collider.restitution, collider.friction))
        elif isinstance(shape, (Box, Sphere)):
            shapes.append(shape)
            owner.append(-1)
            restitution.append(collider.restitution)
            friction.append(collider.friction)
        else:
            meshes.append((shape.bvh, collider.restitution, collider.friction))
    resting = entity.resting_speed
    if resting is None:
        resting = 2.0 * math.hypot(*context.gravity) * context.h  # Mirtich & Canny 1995
    dynamic = np.array([body.motion == "dynamic" for _, body in chosen])
    stage = BodyContacts(
        BodyPieces.of(shapes, owner, restitution, friction),
        bodies.mass,
        bodies.inertia,
        dynamic,
        _planes(planes),
        meshes=meshes,
        iterations=entity.iterations,
        resting_speed=resting,
        restitution=entity.restitution,
        friction=entity.friction,
        gravity=context.scene.world.gravity,
        impacts=entity.impacts,
        time_of_impact=entity.time_of_impact,
        body_time_of_impact=[body.time_of_impact for _, body in chosen],
        particles=_members(entity, context),
    )
    if entity.response == "penalty":
        damping = entity.damping
        if damping is None:
            lightest = float(bodies.mass[dynamic].min()) if dynamic.any() else 1.0
            damping = 2.0 * math.sqrt(entity.stiffness * lightest)  # critical, for the lightest
        context.body_forces.append(BodyPenalty(stage, entity.stiffness, damping))
    else:
        context.stages.append(stage)


def _members(entity: BodyContactSettings, context: BuildContext) -> ParticleMembers | None:
    """The particles that meet the bodies, if the entity names any."""
    if entity.particles is None or not context.particle_count:
        return None
    mask = np.zeros(context.particle_count, dtype=np.bool_)
    mask[context.targets(entity.particles).indices] = True
    arrays = context.arrays
    inverse = np.where(arrays["pinned"], 0.0, 1.0 / arrays["mass"])
    return ParticleMembers(mask, inverse, entity.particle_restitution, entity.particle_friction)


def _planes(planes: list[tuple[Plane, float, float]]) -> Planes:
    if not planes:
        return Planes.none()
    return Planes(
        np.array([p.point for p, _, _ in planes], dtype=np.float64),
        np.array([p.unit_normal for p, _, _ in planes], dtype=np.float64),
        np.array([p.thickness for p, _, _ in planes], dtype=np.float64),
        np.array([e for _, e, _ in planes], dtype=np.float64),
        np.array([mu for _, _, mu in planes], dtype=np.float64),
    )


def _pieces(where: str, body: Any, origin: np.ndarray) -> list[Any]:
    """The body's convex pieces in its axes, measured from its centre of mass (its own origin
    is at ``origin`` from there).

    Raises:
        Located: At the field of a mesh that is not convex, or a piece with no volume.
    """
    at = tuple(float(c) for c in origin)
    if body.convex_pieces is not None:
        pieces = []
        for k, points in enumerate(body.convex_pieces):
            try:
                pieces.append(ConvexHull(np.asarray(points, dtype=np.float64), position=at))
            except ModelError as error:
                raise Located(f"{where}.convex_pieces[{k}]", str(error)) from None
        return pieces
    if body.collision_shape == "none":
        return []
    if body.shape == "sphere":
        return [Sphere(at, body.radius)]
    if body.shape == "box":
        return [Box(at, body.size)]
    if body.shape == "capsule":
        return [Capsule(at, body.radius, body.height)]
    if body.shape == "cylinder":
        return [Cylinder(at, body.radius, body.height)]
    if body.shape == "cone":
        return [Cone(at, body.radius, body.height)]
    if body.shape == "ellipsoid":
        return [Ellipsoid(at, body.size)]
    vertices = np.asarray(body.vertices, dtype=np.float64)
    if body.collision_shape == "decomposition":
        triangles = np.asarray(body.triangles, dtype=np.int64)
        return [
            ConvexHull(piece, position=at) for piece in convex_decomposition(vertices, triangles)
        ]
    if body.collision_shape == "shape":
        volume = enclosed_volume(vertices, np.asarray(body.triangles, dtype=np.int64))
        hull = Qhull(vertices).volume
        if volume < hull * (1.0 - CONVEX_TOLERANCE):
            raise Located(
                f"{where}.vertices",
                f"the mesh is not convex (its volume {volume:.6g} m³ is less than its hull's "
                f"{hull:.6g} m³), and a body collides as convex pieces: give `convex_pieces` "
                '(lists of points in the body\'s axes), collision_shape = "decomposition" to '
                'have it cut into convex pieces, or collision_shape = "hull" to collide as its '
                "convex hull",
            )
    return [ConvexHull(vertices, position=at)]


BUILD = KindBuild(check=_check, finish=_finish)
