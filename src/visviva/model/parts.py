"""The pieces a Model is made of, each from its scene entities: particle arrays, emitters,
forces, the handles and the collision stage.

Every builder here takes the already-checked scene (:mod:`.build` runs the cross-entity checks
first) and refuses what only the physics code can judge — a mesh that is not closed, a
quaternion that is not a rotation — by raising :class:`Located` with the entity's path.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

from ..deformables import (
    DeformableError,
    SpringNetwork,
    cloth_grid,
    cloth_mesh,
    hair,
    rope,
    soft_lattice,
    soft_mesh,
    spring_graph,
)
from ..errors import ModelError, SceneProblem
from ..forces import (
    Attractor,
    Damping,
    Drag,
    Force,
    Gravitation,
    QuadraticDrag,
    Targets,
    UniformGravity,
    Vortex,
)
from ..mechanics.gravity import GRAVITATIONAL_CONSTANT
from ..particles.emitters import SHAPES, EmitterSpec, unit_vector, value_range
from ..particles.handles import HandleMotion, Handles
from .model import ParticleGroup
from .scene import MAX_PARTICLES, Collider, Emitter, ForceField, ParticleCloud, Particles, Scene
from .scene_bodies import (
    BODIES,
    POINT_BODIES,
    Body,
    Cloth,
    ClothMesh,
    Hair,
    Rope,
    SoftLattice,
    SoftMesh,
)
from .scene_crowd import Crowd as CrowdEntity
from .scene_crowd import wall_indices

__all__ = [
    "Located",
    "collision_stage",
    "emitter_specs",
    "force_objects",
    "handle_stage",
    "particle_arrays",
    "penalty_forces",
]


class Located(Exception):
    """A refusal of an entity's values, located at the entity (``entities[i]...``)."""

    def __init__(self, where: str, message: str) -> None:
        super().__init__(message)
        self.problem = SceneProblem(where, message)


def emitter_specs(scene: Scene, names: list[str], duration: float) -> list[EmitterSpec]:
    """The scene's emitters in numbers; slots are assigned by :func:`particle_arrays`
    (``first_slot`` here is their order among emitters, fixed up there)."""
    specs = []
    for index, entity in enumerate(scene.entities):
        if isinstance(entity, Emitter):
            specs.append(_spec(entity, len(specs), names[index], duration, f"entities[{index}]"))
    return specs


def _spec(e: Emitter, index: int, name: str, duration: float, where: str) -> EmitterSpec:
    triangles = np.zeros((0, 3, 3))
    try:
        if e.shape == "mesh":
            vertices = np.asarray(e.vertices, dtype=np.float64)
            corners = np.asarray(e.triangles, dtype=np.int64)
            if corners.min() < 0 or corners.max() >= len(vertices):
                raise ModelError(
                    f"`triangles` refer to vertices outside 0..{len(vertices) - 1}: each index "
                    "must name one of the `vertices`"
                )
            triangles = vertices[corners]
            sides = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
            if not np.linalg.norm(sides, axis=1).sum() > 0.0:
                raise ModelError("the emitter's mesh has no area: its triangles are degenerate")
        spec = EmitterSpec(
            index=index,
            name=name,
            first_slot=0,
            capacity=0,
            rate=e.rate,
            start=e.start,
            stop=math.inf if e.stop is None else e.stop,
            burst_times=np.array([b.time for b in e.bursts], dtype=np.float64),
            burst_counts=np.array([b.count for b in e.bursts], dtype=np.int64),
            shape=SHAPES[e.shape],
            position=np.asarray(e.position, dtype=np.float64),
            radius=e.radius,
            extent=np.asarray(e.extent, dtype=np.float64),
            normal=unit_vector("normal", e.normal),
            surface=e.surface,
            triangles=triangles,
            direction=unit_vector("direction", e.direction),
            spread=math.radians(e.spread_deg),
            speed=value_range("speed", e.speed, positive=False),
            lifetime=value_range("lifetime", e.lifetime, positive=True),
            particle_radius=value_range("particle_radius", e.particle_radius, positive=True),
            mass=e.particle_mass,
            color_ramp=np.asarray(e.color_ramp or [(0.0, *e.color)], dtype=np.float64),
            size_ramp=np.asarray(e.size_ramp or [(0.0, 1.0)], dtype=np.float64),
            seed=e.seed,
        )
    except ModelError as error:
        raise Located(where, str(error)) from None
    if e.rate * duration >= 2.0**53:
        raise Located(
            f"{where}.rate",
            f"{e.rate * duration:.3g} births over the duration; the most an emitter may count is "
            "2^53 (9e15): lower the rate",
        )
    needed = spec.most_alive(duration)
    if e.capacity is None and needed > MAX_PARTICLES:
        raise Located(
            where,
            f"this emitter can have {needed:.3g} particles alive at once (rate × lifetime and "
            f"bursts); the limit is {MAX_PARTICLES}: lower its rate or lifetime, or set "
            "`capacity` (births beyond it are dropped and counted)",
        )
    capacity = e.capacity or max(1, int(needed))
    return _with(spec, capacity=capacity)


def _with(spec: EmitterSpec, **changes: Any) -> EmitterSpec:
    return EmitterSpec(**(vars(spec) | changes))


def particle_arrays(
    scene: Scene, names: list[str], specs: list[EmitterSpec]
) -> tuple[dict[str, np.ndarray], list[ParticleGroup]]:
    """Initial particle state and properties of every particle entity, in entity order; an
    emitter's slots start dead. ``specs`` get their ``first_slot`` (in place in the list)."""
    columns: dict[str, list[np.ndarray]] = {
        k: [] for k in ("position", "velocity", "mass", "radius", "color", "alive", "pinned")
    }
    groups: list[ParticleGroup] = []
    start = 0
    emitted = iter(range(len(specs)))
    for index, entity in enumerate(scene.entities):
        pinned = np.zeros(0, dtype=np.int64)
        mass: float | list[float] | np.ndarray
        if isinstance(entity, Particles):
            x = np.array(entity.positions, dtype=np.float64)
            count = x.shape[0]
            v = np.zeros_like(x) if entity.velocities is None else np.array(entity.velocities)
            color, mass = entity.color, entity.mass
        elif isinstance(entity, BODIES):
            try:
                body = spring_network(entity)
            except ModelError as error:
                raise _located(index, error) from None
            x, mass = body.points, body.mass
            count = x.shape[0]
            if isinstance(entity, POINT_BODIES):
                listed = entity.velocities
                v = np.zeros_like(x) if listed is None else np.array(listed)
            else:
                v = np.broadcast_to(np.asarray(entity.velocity, dtype=np.float64), (count, 3))
            color = entity.color
            pinned = np.array(entity.pinned, dtype=np.int64)
        elif isinstance(entity, ParticleCloud):
            count = entity.count
            rng = np.random.default_rng(entity.seed)
            with np.errstate(over="ignore"):  # an overflow is refused below, by the entity
                offsets = (rng.random((count, 3)) - 0.5) * np.asarray(entity.size)
                x = np.asarray(entity.center) + offsets
                jitter = entity.velocity_jitter * rng.standard_normal((count, 3))
                v = np.asarray(entity.velocity) + jitter
            color, mass = entity.color, entity.mass
        elif isinstance(entity, Emitter):
            k = next(emitted)
            specs[k] = _with(specs[k], first_slot=start)
            count = specs[k].capacity
            x = v = np.zeros((count, 3))
            color, mass = tuple(specs[k].color_ramp[0, 1:]), specs[k].mass
        else:
            continue
        columns["position"].append(x)
        columns["velocity"].append(np.asarray(v, dtype=np.float64))
        radius = specs[k].particle_radius[0] if isinstance(entity, Emitter) else entity.radius
        columns["mass"].append(np.broadcast_to(np.asarray(mass, dtype=np.float64), (count,)))
        columns["radius"].append(np.broadcast_to(np.asarray(radius, dtype=np.float64), (count,)))
        columns["color"].append(np.broadcast_to(np.asarray(color, dtype=np.float64), (count, 3)))
        columns["alive"].append(np.full(count, not isinstance(entity, Emitter)))
        held = np.zeros(count, dtype=bool)
        held[pinned] = True
        columns["pinned"].append(held)
        groups.append(
            ParticleGroup(names[index], index, start, count, emitted=isinstance(entity, Emitter))
        )
        start += count
    empty = {"position": (0, 3), "velocity": (0, 3), "color": (0, 3)}
    arrays = {
        name: np.concatenate(parts) if parts else np.zeros(empty.get(name, (0,)))
        for name, parts in columns.items()
    }
    arrays["alive"] = arrays["alive"].astype(bool)
    arrays["pinned"] = arrays["pinned"].astype(bool)
    return arrays, groups


def handle_stage(
    scene: Scene, groups: Sequence[ParticleGroup], arrays: dict[str, np.ndarray]
) -> Handles | None:
    """The handles of the scene's bodies (``None`` if none has one); the handled particles'
    ``position`` and ``velocity`` in ``arrays`` are set (in place) to their handles' at t = 0.

    Raises:
        Located: For a handle whose path leaves the range of a float within the run.
    """
    starts = {g.entity: g.start for g in groups}
    motions, particles = [], []
    for index, entity in enumerate(scene.entities):
        if not isinstance(entity, BODIES) or entity.handle is None:
            continue
        held = starts[index] + np.array(sorted(set(entity.pinned)), dtype=np.int64)
        where = f"entities[{index}].handle"
        motion = _motion(entity.handle, arrays["position"][held], where)
        travel, turn, spin = motion.largest_extent(scene.integration.duration)
        reach = float(np.abs(arrays["position"][held] - motion.pivot).max()) + travel
        if not all(math.isfinite(v) and v < 1e300 for v in (reach, turn, spin * reach)):
            raise Located(
                where,
                "this motion takes the points beyond the range of a float within the run's "
                f"duration ({scene.integration.duration!r} s): use smaller speeds or other units",
            )
        motions.append(motion)
        particles.append(held)
    if not motions:
        return None
    stage = Handles(motions, particles, [arrays["position"][p] for p in particles])
    arrays["position"][stage.indices], arrays["velocity"][stage.indices] = stage.place(0.0)
    return stage


def _motion(handle: Any, points: np.ndarray, where: str) -> HandleMotion:
    """A handle's schema in numbers (the pivot by default at its ``points``' centroid)."""
    pivot = points.mean(axis=0) if handle.pivot is None else np.array(handle.pivot, dtype=float)
    axis = np.array([0.0, 1.0, 0.0])
    if handle.turns:
        try:
            axis = unit_vector("axis", handle.axis)
        except ModelError as error:
            raise Located(f"{where}.axis", str(error)) from None
    return HandleMotion(
        pivot=pivot,
        velocity=np.array(handle.velocity, dtype=np.float64),
        axis=axis,
        angular_velocity=handle.angular_velocity,
        amplitude=handle.amplitude,
        frequency=handle.frequency,
        start=handle.start,
        stop=math.inf if handle.stop is None else handle.stop,
        ramp=handle.ramp,
    )


def _targets(entity: ForceField | Collider, groups: Sequence[ParticleGroup], count: int) -> Targets:
    if entity.targets is None:
        return Targets(count)
    chosen = [g for g in groups if g.name in entity.targets]
    indices = [np.arange(g.start, g.start + g.count) for g in chosen]
    return Targets(count, np.concatenate(indices) if indices else np.zeros(0, np.int64))


def force_objects(scene: Scene, groups: Sequence[ParticleGroup], mass: np.ndarray) -> list[Force]:
    """World gravity (on every particle, if not zero) and each force entity."""
    count = mass.shape[0]
    forces: list[Force] = []
    if count and any(scene.world.gravity):
        forces.append(UniformGravity(scene.world.gravity, mass))
    for index, entity in enumerate(scene.entities):
        if isinstance(entity, ForceField):
            try:
                forces.append(_force(entity, _targets(entity, groups, count), mass))
            except ModelError as error:
                raise Located(f"entities[{index}]", str(error)) from None
    return forces


def _force(e: ForceField, targets: Targets, mass: np.ndarray) -> Force:
    zero = (0.0, 0.0, 0.0)
    if e.kind in ("drag", "wind"):
        return Drag(e.coefficient, mass, targets, air_velocity=e.velocity or zero)  # type: ignore[arg-type]
    if e.kind == "quadratic_drag":
        return QuadraticDrag(e.coefficient, mass, targets, air_velocity=e.velocity or zero)  # type: ignore[arg-type]
    if e.kind == "damping":
        return Damping(e.rate, mass, targets)  # type: ignore[arg-type]
    if e.kind == "attractor":
        softening = 0.1 if e.softening is None else e.softening
        return Attractor(e.point, e.strength, mass, targets, softening=softening)  # type: ignore[arg-type]
    if e.kind == "vortex":
        return Vortex(
            e.point or zero,
            e.axis or (0.0, 1.0, 0.0),
            e.circulation,  # type: ignore[arg-type]
            e.coefficient,  # type: ignore[arg-type]
            mass,
            targets,
            core_radius=0.5 if e.core_radius is None else e.core_radius,
        )
    return Gravitation(
        mass,
        targets,
        G=GRAVITATIONAL_CONSTANT if e.G is None else e.G,
        softening=e.softening or 0.0,
        method=e.method or "direct",
        theta=0.5 if e.theta is None else e.theta,
    )


def _located(index: int, error: ModelError, field: str | None = None) -> Located:
    """``error`` located at ``entities[index]``: at the field and item a
    :class:`~visviva.deformables.DeformableError` names, else at ``field`` if given."""
    where = f"entities[{index}]"
    if isinstance(error, DeformableError):
        where += f".{error.field}" + ("" if error.index is None else f"[{error.index}]")
    elif field is not None:
        where += f".{field}"
    return Located(where, str(error))


def spring_forces(scene: Scene, groups: Sequence[ParticleGroup], count: int) -> list[Force]:
    """The springs of each deformable body (see :mod:`visviva.deformables`), each at rest at
    its initial length unless the body gives its rest lengths."""
    from ..forces import Springs

    forces: list[Force] = []
    starts = {g.entity: g.start for g in groups}
    for index, entity in enumerate(scene.entities):
        if not isinstance(entity, BODIES):
            continue
        try:
            network = spring_network(entity)
            rest = network.rest_length()
        except ModelError as error:
            raise _located(index, error, _placed_by(entity)) from None
        first = starts[index]
        pairs = network.pairs + first
        lattice = None if network.lattice is None else (network.lattice, first)
        forces.append(Springs(pairs, rest, network.stiffness, entity.damping, count, lattice))
    return forces


def _placed_by(entity: Body) -> str:
    """The field that places a body's points (where points too close or too far are fixed)."""
    if isinstance(entity, (Cloth, SoftLattice)):
        return "resolution"
    if isinstance(entity, (ClothMesh, SoftMesh)):
        return "vertices"
    return "points"


def body_networks(
    scene: Scene, groups: Sequence[ParticleGroup]
) -> Iterator[tuple[SpringNetwork, int]]:
    """Each deformable body's network and the index of its first particle in the scene (a
    body's point ``i`` is the scene's ``first + i``)."""
    starts = {g.entity: g.start for g in groups}
    for index, entity in enumerate(scene.entities):
        if isinstance(entity, BODIES):
            yield spring_network(entity), starts[index]


def spring_network(entity: Body) -> SpringNetwork:
    """The particles and springs of a deformable body entity.

    Raises:
        ModelError: A :class:`~visviva.deformables.DeformableError` naming the field and item
            at fault, or a body beyond what a float holds.
    """
    if isinstance(entity, ClothMesh):
        return cloth_mesh(
            np.array(entity.vertices, dtype=np.float64),
            np.array(entity.triangles, dtype=np.int64).reshape(-1, 3),
            entity.areal_density,
            entity.stiffness,
            entity.bending,
        )
    if isinstance(entity, SoftMesh):
        return soft_mesh(
            np.array(entity.vertices, dtype=np.float64),
            np.array(entity.tetrahedra, dtype=np.int64).reshape(-1, 4),
            entity.density,
            entity.stiffness,
        )
    if isinstance(entity, POINT_BODIES):
        points = np.array(entity.points, dtype=np.float64)
        mass = np.broadcast_to(np.asarray(entity.mass, dtype=np.float64), (points.shape[0],))
        if isinstance(entity, Rope):
            return rope(points, mass, entity.stiffness, entity.bending)
        if isinstance(entity, Hair):
            return hair(points, mass, entity.stiffness, entity.bending, entity.torsion)
        rest = None if entity.rest_length is None else np.asarray(entity.rest_length)
        stiffness = np.asarray(entity.stiffness, dtype=np.float64)
        return spring_graph(points, mass, np.array(entity.pairs), stiffness, rest)
    if isinstance(entity, SoftLattice):
        return soft_lattice(
            np.asarray(entity.origin, dtype=np.float64),
            np.asarray(entity.size, dtype=np.float64),
            entity.resolution,
            entity.density,
            entity.stiffness,
            entity.stiffness if entity.shear is None else entity.shear,
            entity.stiffness if entity.diagonal is None else entity.diagonal,
        )
    return cloth_grid(
        np.asarray(entity.origin, dtype=np.float64),
        np.asarray(entity.along, dtype=np.float64),
        np.asarray(entity.across, dtype=np.float64),
        entity.resolution,
        entity.areal_density,
        entity.stiffness,
        entity.stiffness if entity.shear is None else entity.shear,
        entity.bending,
    )


def _colliders(scene: Scene, response: str) -> list[tuple[int, Collider]]:
    """The colliders of one response, planes first (the kernels' fast path; see
    :class:`~visviva.collision.ColliderSet`)."""
    chosen = [
        (i, e)
        for i, e in enumerate(scene.entities)
        if isinstance(e, Collider) and e.response == response
    ]
    return sorted(chosen, key=lambda pair: pair[1].shape != "plane")


def _shape(e: Collider, where: str) -> Any:
    from ..collision import Box, Plane, Sphere, TriangleMesh

    zero = (0.0, 0.0, 0.0)
    try:
        if e.shape == "plane":
            thickness = math.inf if e.thickness is None else e.thickness
            return Plane(e.point or zero, e.normal or (0.0, 1.0, 0.0), thickness)
        if e.shape == "sphere":
            return Sphere(e.center or zero, e.radius)
        if e.shape == "box":
            return Box(e.center or zero, e.size, e.orientation or (1.0, 0.0, 0.0, 0.0))
        return TriangleMesh(np.asarray(e.vertices), np.asarray(e.triangles))
    except ModelError as error:
        raise Located(where, str(error)) from None


def collision_stage(
    scene: Scene, groups: Sequence[ParticleGroup], pinned: np.ndarray, h: float
) -> Any:
    """The collision stage of the impulse colliders, or ``None`` if there are none (``pinned``
    particles meet none: nothing moves them)."""
    from ..collision import MAX_COLLIDERS, ColliderResponse, ColliderSet, ParticleCollisions

    chosen = _colliders(scene, "impulse")
    if not chosen or not pinned.shape[0]:
        return None
    if len(chosen) > MAX_COLLIDERS:
        raise Located(
            f"entities[{chosen[MAX_COLLIDERS][0]}]",
            f"a scene may hold at most {MAX_COLLIDERS} impulse colliders",
        )
    shapes = [_shape(e, f"entities[{i}]") for i, e in chosen]
    masks = _masks(chosen, groups, pinned, scene)
    if not masks.any():  # no particle meets them (pinned ones, a crowd's agents its walls)
        return None
    response = ColliderResponse(
        restitution=[e.restitution for _, e in chosen],
        friction=[e.friction for _, e in chosen],
        resting_speed=_resting_speeds(scene, chosen, h),
        time_of_impact=[e.time_of_impact for _, e in chosen],
    )
    return ParticleCollisions(ColliderSet(shapes), response, masks, _labels(chosen))


def penalty_forces(
    scene: Scene, groups: Sequence[ParticleGroup], arrays: dict[str, np.ndarray], h: float
) -> list[Force]:
    """The penalty-contact force of the penalty colliders (empty list if there are none), on
    the particles' ``arrays`` (``mass``, ``radius``, ``pinned``); ``h`` [s] is the integrator
    step (a contact rests below the speed gravity gives in two)."""
    from ..collision import ColliderSet, PenaltyContact

    chosen = _colliders(scene, "penalty")
    if not chosen or not arrays["mass"].shape[0]:
        return []
    shapes = [_shape(e, f"entities[{i}]") for i, e in chosen]
    masks = _masks(chosen, groups, arrays["pinned"], scene)
    if not masks.any():
        return []
    return [
        PenaltyContact(
            ColliderSet(shapes),
            stiffness=[e.stiffness for _, e in chosen],  # type: ignore[misc]
            damping=[e.damping or 0.0 for _, e in chosen],
            masks=masks,
            radius=arrays["radius"],
            labels=_labels(chosen),
            resting_speed=_resting_speeds(scene, chosen, h),
        )
    ]


def _masks(
    chosen: Sequence[tuple[int, Collider]],
    groups: Sequence[ParticleGroup],
    pinned: np.ndarray,
    scene: Scene,
) -> np.ndarray:
    """Bit ``k`` of ``masks[i]`` set where particle ``i`` meets collider ``k`` (pinned
    particles meet none; a crowd's agents meet its walls through the crowd's forces only)."""
    count = pinned.shape[0]
    masks = np.zeros(count, dtype=np.uint64)
    for bit, (_, e) in enumerate(chosen):
        masks[_targets(e, groups, count).indices] |= np.uint64(1) << np.uint64(bit)
    for crowd in (e for e in scene.entities if isinstance(e, CrowdEntity)):
        walls = wall_indices(crowd, scene.entities)
        agents = [g for g in groups if g.name in crowd.targets]
        for bit, (index, _) in enumerate(chosen):
            if index in walls:
                for g in agents:
                    masks[g.start : g.start + g.count] &= ~(np.uint64(1) << np.uint64(bit))
    masks[pinned] = 0
    return masks


def _resting_speeds(scene: Scene, chosen: Sequence[tuple[int, Collider]], h: float) -> list[float]:
    """Each collider's resting speed [m/s]: by default, the speed gravity gives in two steps
    of ``h`` (Mirtich & Canny 1995)."""
    gravity = math.hypot(*scene.world.gravity)  # no overflow for huge components
    return [2.0 * gravity * h if e.resting_speed is None else e.resting_speed for _, e in chosen]


def _labels(chosen: Sequence[tuple[int, Collider]]) -> list[str]:
    """Each collider's name, or where it is in the scene."""
    return [e.name or f"entities[{i}]" for i, e in chosen]
