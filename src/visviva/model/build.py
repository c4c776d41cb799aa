"""From a validated :class:`~visviva.model.scene.Scene` to the frozen :class:`Model`.

Mesh files are read first (:mod:`.scene_meshes`). The schema checks each field on its own;
this module checks what spans fields and entities —
list lengths that must agree, unique names, targets that name existing entities, the total
particle count and step count — and reports every problem at once as a
:class:`~visviva.errors.SceneError`. Only then does it allocate the entity arrays and make the
pieces the run needs: the particle forces (world gravity first), the named systems' problems,
and the stages in their order — the bodies' handles, the collisions, the emission
(:mod:`.parts`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .._registry import did_you_mean
from .._validation import describe
from ..errors import ModelError, SceneError, SceneProblem
from ..rigid.projection import BodyProjection
from ..simulation.loop import MAX_STEPS
from .boids_parts import boids_stages, check_flocks
from .contact_parts import check_contacts, contact_stages
from .crowd_parts import crowd_stage
from .model import Integration, Model, SystemInstance, frozen_array
from .parts import (
    Located,
    collision_stage,
    emitter_specs,
    force_objects,
    handle_stage,
    particle_arrays,
    penalty_forces,
    spring_forces,
)
from .rigid_parts import rigid_bodies
from .scene import (
    MAX_PARTICLES,
    Collider,
    Emitter,
    ForceField,
    ParticleCloud,
    Particles,
    Scene,
    System,
)
from .scene_bodies import BODIES, POINT_BODIES, Body, Hair, Rope, SpringGraph
from .scene_boids import Boids
from .scene_contacts import ParticleCollisionSettings
from .scene_crowd import Crowd
from .scene_meshes import with_mesh_files
from .scene_renames import RENAMED_PARAMETERS, renamed_message
from .scene_rigid import RigidBody
from .systems import SYSTEMS

__all__ = ["build_model", "entity_names"]

#: Entities that hold particles (which forces and colliders may target).
PARTICLE_ENTITIES = (Particles, ParticleCloud, *BODIES, Emitter)


def entity_names(scene: Scene) -> list[str]:
    """Each entity's name: its own, or its type and index (``particles0``, ``emitter2``)."""
    return [e.name or f"{e.type}{i}" for i, e in enumerate(scene.entities)]


def build_model(scene: Scene, source: str | None = None) -> Model:
    """Check ``scene`` as a whole and build its :class:`Model`.

    Args:
        scene: A validated scene (from a file or a builder).
        source: The scene file's text, if it came from one (kept in recordings).

    Raises:
        SceneError: Listing every problem found.
    """
    scene = with_mesh_files(scene)  # mesh files read: from here on, every mesh is arrays
    problems = _check(scene)
    if problems:
        raise SceneError(problems)
    settings = scene.integration
    names = entity_names(scene)
    try:
        specs = emitter_specs(scene, names, settings.duration)
    except Located as located:
        raise SceneError([located.problem]) from None
    slots = sum(s.capacity for s in specs) + sum(
        _count(e) for e in scene.entities if isinstance(e, (Particles, ParticleCloud, *BODIES))
    )
    if slots > MAX_PARTICLES:
        raise SceneError(
            [
                SceneProblem(
                    "entities",
                    f"{slots} particle slots in all (emitters count their capacity); the limit "
                    f"is {MAX_PARTICLES}",
                )
            ]
        )
    try:
        arrays, groups = particle_arrays(scene, names, specs)
    except Located as located:
        raise SceneError([located.problem]) from None
    count = arrays["position"].shape[0]
    h = settings.dt / settings.substeps
    try:
        systems = _systems(scene, names)
        stages: list[Any] = []
        stages += boids_stages(scene, groups, arrays)
        crowd = crowd_stage(scene, names, groups, arrays, h)
        if crowd is not None:
            stages.append(crowd)
        handles = handle_stage(scene, groups, arrays)
        if handles is not None:
            stages.append(handles)
        with np.errstate(all="ignore"):  # overflowing values are judged by the start check
            forces = force_objects(scene, groups, arrays["mass"])
            penalties = penalty_forces(scene, groups, arrays, h)
            forces += penalties
            forces += spring_forces(scene, groups, count)
        with np.errstate(over="ignore"):  # a weight beyond the float range diverges, named
            bodies, body_forces = rigid_bodies(scene, names)
        collisions = collision_stage(scene, groups, arrays["pinned"], h)
        stages += contact_stages(scene, groups, arrays, collisions, h)
        if collisions is not None:
            stages.append(collisions)
        if specs:
            from ..particles.emission import Emission

            stages.append(Emission(specs, arrays["alive"], arrays["radius"]))
        if bodies is not None:
            stages.append(BodyProjection(bodies.count))
    except Located as located:
        raise SceneError([located.problem]) from None
    model = Model(
        name=scene.scene.name,
        scene=scene,
        gravity=frozen_array(scene.world.gravity),
        integration=Integration(
            method=settings.method,
            dt=settings.dt,
            duration=settings.duration,
            substeps=settings.substeps,
            record_every=settings.record_every or Integration.default_record_every(settings.dt),
            energy_tolerance=settings.energy_tolerance,
        ),
        particle_position=frozen_array(arrays["position"]),
        particle_velocity=frozen_array(arrays["velocity"]),
        particle_mass=frozen_array(arrays["mass"]),
        particle_radius=frozen_array(arrays["radius"]),
        particle_color=frozen_array(arrays["color"]),
        particle_alive=frozen_array(arrays["alive"], dtype=bool),
        particle_pinned=frozen_array(arrays["pinned"], dtype=bool),
        particle_groups=tuple(groups),
        systems=tuple(systems),
        bodies=bodies,
        body_forces=tuple(body_forces),
        forces=tuple(forces),
        emitters=tuple(specs),
        stages=tuple(sorted(stages, key=lambda stage: stage.phase)),
        contact_sources=(*([] if collisions is None else [collisions]), *penalties),
        output_formats=tuple(scene.output.formats),
        output_fps=scene.output.fps,
        output_speed=scene.output.speed,
        output_trail=scene.output.trail,
        output_color_by=scene.output.color_by,
        source=source,
    )
    problems = _check_start(model)
    if problems:
        raise SceneError(problems)
    return model


def _systems(scene: Scene, names: list[str]) -> list[SystemInstance]:
    systems, offset = [], 0
    for index, entity in enumerate(scene.entities):
        if not isinstance(entity, System):
            continue
        kind = SYSTEMS[entity.system]
        values = {k: p.default for k, p in kind.parameters.items()} | dict(entity.parameters)
        where = f"entities[{index}].parameters"
        try:
            with np.errstate(all="ignore"):  # overflow is judged by the start check
                problem = kind.build(values, np.asarray(scene.world.gravity))
        except ModelError as error:
            problem = _located(str(error), where, values)
            raise Located(problem.path, problem.message) from None
        except (OverflowError, ZeroDivisionError, FloatingPointError, ValueError):
            raise Located(where, _OVERFLOW) from None
        systems.append(SystemInstance(names[index], entity.system, values, index, offset, problem))
        offset += problem.size
    return systems


_OVERFLOW = (
    "these values overflow a float while the system is set up (the largest float is 1.8e308): "
    "use smaller values or other units"
)
_NOT_FINITE = (
    "these values give a non-finite initial acceleration or energy (a mass, speed, length or "
    "position too large or too small to compute with, beyond ±1.8e308): use other values or units"
)


def _check_start(model: Model) -> list[SceneProblem]:
    """Problems only the built model shows: a state that overflowed while being placed, or
    values that cannot give a finite start (``omega = 1e200`` squares to inf, a mass of 1e200
    at 10 m/s has an infinite kinetic energy).

    The model's system is built and its initial acceleration and energy are evaluated once, so
    a scene that ``visviva validate`` accepts also starts in ``visviva run``.
    """
    for name in ("particle_position", "particle_velocity"):
        bad = ~np.isfinite(getattr(model, name))
        if bad.any():
            index = int(np.argwhere(bad)[0][0])
            group = next(g for g in model.particle_groups if g.start <= index < g.start + g.count)
            return [
                SceneProblem(
                    f"entities[{group.entity}]",
                    f"particle {index - group.start} starts with a non-finite "
                    f"{name.removeprefix('particle_')}: the values overflow a float",
                )
            ]
    where = "entities"
    values: Mapping[str, float] = {}
    if model.systems:
        where = f"entities[{model.systems[0].entity}].parameters"
        values = model.systems[0].parameters
    try:
        with np.errstate(all="ignore"):  # overflow is judged by the results below
            system = model.system()
            start = model.initial_state()
            results = [*system.derivative(start.t, start.parts)]
            results.append(np.asarray(system.energy(start)))
    except ModelError as error:
        return [_located(str(error), where, values)]
    except (OverflowError, ZeroDivisionError, FloatingPointError, ValueError):
        return [SceneProblem(where, _OVERFLOW)]
    if not all(np.isfinite(v).all() for v in results):
        return [SceneProblem(where, _NOT_FINITE)]
    return []


def _located(message: str, where: str, values: Mapping[str, float]) -> SceneProblem:
    """A system's own refusal, at the parameter its message names ("`eccentricity` must ...");
    the gravity a system takes from the world ("`g` must ...") is the world's."""
    if message.startswith("`") and message.count("`") >= 2:
        name, rest = message[1:].split("`", 1)
        if name == "g":
            return SceneProblem(
                "world.gravity", "this system moves under gravity: it must not be zero"
            )
        if name in values:
            return SceneProblem(f"{where}.{name}", rest.strip())
    return SceneProblem(where, message)


def _check(scene: Scene) -> list[SceneProblem]:
    problems: list[SceneProblem] = []
    entities = scene.entities
    if not any(isinstance(e, (*PARTICLE_ENTITIES, System, RigidBody)) for e in entities):
        what = "nothing in this scene moves" if entities else "the scene is empty"
        problems.append(
            SceneProblem(
                "entities",
                f'{what}; add at least one [[entities]] table of type "particles", '
                '"particle_cloud", "emitter", "body" or "system"',
            )
        )
    problems += _check_steps(scene)
    names = entity_names(scene)
    seen: dict[str, int] = {}
    total = 0
    for index, entity in enumerate(entities):
        where = f"entities[{index}]"
        if entity.name is not None:
            if entity.name in seen:
                problems.append(
                    SceneProblem(
                        f"{where}.name",
                        f"duplicate name: entities[{seen[entity.name]}] already uses it; "
                        "names must be unique",
                        describe(entity.name),
                    )
                )
            else:
                seen[entity.name] = index
        if isinstance(entity, (Particles, *POINT_BODIES)):
            total += _count(entity)
            problems += _check_lengths(entity, where)
        elif isinstance(entity, (ParticleCloud, *BODIES)):
            total += _count(entity)
        elif isinstance(entity, System):
            problems += _check_system(entity, where)
    if total > MAX_PARTICLES:
        problems.append(
            SceneProblem(
                "entities",
                f"{total} particles in all; the limit is {MAX_PARTICLES} (about 2.4 GB of state)",
            )
        )
    problems += _check_targets(scene, names)
    holders = [names[i] for i, e in enumerate(entities) if isinstance(e, PARTICLE_ENTITIES)]
    problems += check_flocks(scene, holders)
    problems += check_contacts(scene)
    problems += _check_first_order(scene)
    return problems


def _check_steps(scene: Scene) -> list[SceneProblem]:
    dt, duration = scene.integration.dt, scene.integration.duration
    if dt > duration:
        return [
            SceneProblem(
                "integration.dt",
                f"the step is longer than the duration ({duration!r} s); use dt <= duration",
                repr(dt),
            )
        ]
    steps = duration / dt * scene.integration.substeps
    if steps > MAX_STEPS:
        return [
            SceneProblem(
                "integration.dt",
                f"{steps:.3g} integrator steps (substeps included) to reach the duration; the "
                f"limit is {MAX_STEPS:.0e}",
                repr(dt),
            )
        ]
    return []


def _check_targets(scene: Scene, names: list[str]) -> list[SceneProblem]:
    """Targets must name entities that hold particles; gravitation may not target emitters."""
    holders = {
        names[i]: e for i, e in enumerate(scene.entities) if isinstance(e, PARTICLE_ENTITIES)
    }
    problems = []
    for index, entity in enumerate(scene.entities):
        targeting = (ForceField, Collider, Boids, ParticleCollisionSettings, Crowd)
        if not isinstance(entity, targeting) or entity.targets is None:
            continue
        for k, target in enumerate(entity.targets):
            where = f"entities[{index}].targets[{k}]"
            if target not in holders:
                problems.append(
                    SceneProblem(
                        where,
                        f"no particle entity is called {target!r}.{did_you_mean(target, holders)}"
                        f" Particle entities: {', '.join(holders) or 'none'}",
                    )
                )
            elif (
                isinstance(entity, ForceField)
                and entity.kind == "gravitation"
                and isinstance(holders[target], Emitter)
            ):
                problems.append(
                    SceneProblem(
                        where,
                        "gravitation acts among particles that live for the whole run; an "
                        "emitter's particles are born and die (target particles or a "
                        "particle_cloud instead)",
                    )
                )
    return problems


def _check_first_order(scene: Scene) -> list[SceneProblem]:
    """A first-order system (Dahlquist's test equation) has no positions to mix with others."""
    for index, entity in enumerate(scene.entities):
        if isinstance(entity, System) and entity.system == "test-equation":
            moving = [e for e in scene.entities if isinstance(e, (*PARTICLE_ENTITIES, System))]
            if len(moving) > 1:
                return [
                    SceneProblem(
                        f"entities[{index}]",
                        "the test equation is a first-order system without positions: put it "
                        "in a scene of its own",
                    )
                ]
    return []


def _count(entity: Particles | ParticleCloud | Body) -> int:
    """How many particles an entity that lists or counts them holds."""
    if isinstance(entity, Particles):
        return len(entity.positions)
    if isinstance(entity, ParticleCloud):
        return entity.count
    return entity.point_count


def _check_lengths(entity: Particles | Rope | Hair | SpringGraph, where: str) -> list[SceneProblem]:
    count = _count(entity)
    problems = []
    for name in ("velocities", "mass", "radius"):
        value = getattr(entity, name)
        if isinstance(value, list) and len(value) != count:
            problems.append(
                SceneProblem(
                    f"{where}.{name}",
                    f"has {len(value)} entries for {count} positions; give one per particle"
                    + (" or a single value" if name != "velocities" else ""),
                )
            )
    return problems


def _check_system(entity: System, where: str) -> list[SceneProblem]:
    kind = SYSTEMS[entity.system]
    renamed = RENAMED_PARAMETERS.get(entity.system)
    problems = []
    for key, value in entity.parameters.items():
        path = f"{where}.parameters.{key}"
        new = None if renamed is None else renamed.get(key)
        if new is not None:
            problems.append(
                SceneProblem(
                    path, renamed_message(key, new, f"the {entity.system} system", "parameter")
                )
            )
            continue
        if key not in kind.parameters:
            problems.append(
                SceneProblem(
                    path,
                    f"{entity.system} has no parameter {key!r}.{did_you_mean(key, kind.parameters)}"
                    f" Parameters: {', '.join(kind.parameters)}",
                )
            )
            continue
        parameter = kind.parameters[key]
        if parameter.positive and value <= 0:
            problems.append(SceneProblem(path, f"must be positive [{parameter.unit}]", repr(value)))
        if parameter.integer and value != int(value):
            problems.append(SceneProblem(path, "must be a whole number", repr(value)))
        if parameter.minimum is not None and value < parameter.minimum:
            problems.append(
                SceneProblem(path, f"must be at least {parameter.minimum:g}", repr(value))
            )
        if parameter.maximum is not None and value > parameter.maximum:
            problems.append(
                SceneProblem(path, f"must be at most {parameter.maximum:g}", repr(value))
            )
    return problems
