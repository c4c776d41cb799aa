"""From a validated :class:`~visviva.io.scene_schema.Scene` to the frozen :class:`Model`.

The schema checks each field on its own; this module checks what spans fields and entities —
list lengths that must agree, unique names, known systems and parameters, what may be mixed,
the total particle count and step count — and reports every problem at once as a
:class:`~visviva.errors.SceneError`. Only then does it allocate the particle arrays.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .._validation import describe, did_you_mean
from ..errors import ModelError, SceneError, SceneProblem
from ..io.scene_schema import MAX_PARTICLES, ParticleCloud, Particles, Scene, System
from ..ode.problems import SecondOrderProblem
from ..simulation.loop import MAX_STEPS
from .model import Integration, Model, ParticleGroup, SystemInstance, frozen_array
from .systems import SYSTEMS

__all__ = ["build_model"]


def build_model(scene: Scene, source: str | None = None) -> Model:
    """Check ``scene`` as a whole and build its :class:`Model`.

    Args:
        scene: A validated scene (from a file or a builder).
        source: The scene file's text, kept in the model for recordings.

    Raises:
        SceneError: Listing every problem found.
    """
    problems = _check(scene)
    if problems:
        raise SceneError(problems)
    particles = [e for e in scene.entities if not isinstance(e, System)]
    systems = [e for e in scene.entities if isinstance(e, System)]
    integration = scene.integration
    position, velocity, mass, radius, groups = _particle_arrays(particles)
    system = None
    if systems:
        entity = systems[0]
        kind = SYSTEMS[entity.system]
        values = {k: p.default for k, p in kind.parameters.items()} | dict(entity.parameters)
        system = SystemInstance(entity.name or entity.system, entity.system, values)
    model = Model(
        name=scene.scene.name,
        gravity=frozen_array(scene.world.gravity),
        integration=Integration(
            method=integration.method,
            dt=integration.dt,
            duration=integration.duration,
            substeps=integration.substeps,
            record_every=integration.record_every
            or Integration.default_record_every(integration.dt),
            energy_tolerance=integration.energy_tolerance,
        ),
        particle_position=position,
        particle_velocity=velocity,
        particle_mass=mass,
        particle_radius=radius,
        particle_groups=groups,
        system=system,
        output_formats=tuple(scene.output.formats),
        output_fps=scene.output.fps,
        output_speed=scene.output.speed,
        output_trail=scene.output.trail,
        source=source,
    )
    problems = _check_start(model, scene)
    if problems:
        raise SceneError(problems)
    return model


def _check_start(model: Model, scene: Scene) -> list[SceneProblem]:
    """Problems only the built model shows: a state that overflowed while being placed, or
    values that cannot give a finite start (``omega = 1e200`` squares to inf, a mass of 1e200
    at 10 m/s has an infinite kinetic energy).

    The model's problem is built and its initial acceleration and energy are evaluated once, so
    a scene that ``visviva validate`` accepts also starts in ``visviva run``.
    """
    if model.system is None:
        for name in ("particle_position", "particle_velocity"):
            bad = ~np.isfinite(getattr(model, name))
            if bad.any():
                index = int(np.argwhere(bad)[0][0])
                entity, group = next(
                    (k, g)
                    for k, g in enumerate(model.particle_groups)
                    if g.start <= index < g.start + g.count
                )
                return [
                    SceneProblem(
                        f"entities[{entity}]",
                        f"particle {index - group.start} starts with a non-finite "
                        f"{name.removeprefix('particle_')}: the values overflow a float",
                    )
                ]
        where = "entities"
        values: Mapping[str, float] = {}
    else:
        index = next(i for i, e in enumerate(scene.entities) if isinstance(e, System))
        where = f"entities[{index}].parameters"
        values = model.system.parameters
    try:
        with np.errstate(all="ignore"):  # overflow is judged by the results below
            problem = model.problem()
            system = problem.system()
            start = problem.initial_state()
            values_at_start = [*system.derivative(start.t, start.parts)]
            if system.has_energy:
                values_at_start.append(np.asarray(system.energy(start)))
    except ModelError as error:
        if model.system is None:
            return [SceneProblem(where, _NOT_FINITE)]
        return [_located(str(error), where, values)]
    except (OverflowError, ZeroDivisionError, FloatingPointError, ValueError):
        return [
            SceneProblem(
                where,
                "these values overflow a float while the system is set up (the largest float "
                "is 1.8e308): use smaller values or other units",
            )
        ]
    if not all(np.isfinite(v).all() for v in values_at_start):
        return [SceneProblem(where, _NOT_FINITE)]
    return []


_NOT_FINITE = (
    "these values give a non-finite initial acceleration or energy (a mass, speed, length or "
    "position too large or too small to compute with, beyond ±1.8e308): use other values or units"
)


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
    if not entities:
        problems.append(
            SceneProblem(
                "entities",
                "the scene is empty; add at least one [[entities]] table "
                '(type = "particles", "particle_cloud" or "system")',
            )
        )
    dt, duration = scene.integration.dt, scene.integration.duration
    if dt > duration:
        problems.append(
            SceneProblem(
                "integration.dt",
                f"the step is longer than the duration ({duration!r} s); use dt <= duration",
                repr(dt),
            )
        )
    elif duration / dt * scene.integration.substeps > MAX_STEPS:
        steps = duration / dt * scene.integration.substeps
        problems.append(
            SceneProblem(
                "integration.dt",
                f"{steps:.3g} integrator steps (substeps included) to reach the duration; the "
                f"limit is {MAX_STEPS:.0e}",
                repr(dt),
            )
        )
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
        if isinstance(entity, Particles):
            total += len(entity.positions)
            problems += _check_lengths(entity, where)
        elif isinstance(entity, ParticleCloud):
            total += entity.count
        else:
            problems += _check_system(entity, where)
    if total > MAX_PARTICLES:
        problems.append(
            SceneProblem(
                "entities",
                f"{total} particles in all; the limit is {MAX_PARTICLES} (about 2.4 GB of state)",
            )
        )
    systems = [i for i, e in enumerate(entities) if isinstance(e, System)]
    if systems and len(systems) != len(entities):
        problems.append(
            SceneProblem(
                f"entities[{systems[0]}]",
                "a named system runs on its own: put it in a scene without particles",
            )
        )
    elif len(systems) > 1:
        problems.append(
            SceneProblem(f"entities[{systems[1]}]", "a scene holds at most one named system")
        )
    return problems


def _check_lengths(entity: Particles, where: str) -> list[SceneProblem]:
    count = len(entity.positions)
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
    problems = []
    for key, value in entity.parameters.items():
        path = f"{where}.parameters.{key}"
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


def _particle_arrays(
    entities: list[Particles | ParticleCloud],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, tuple[ParticleGroup, ...]]:
    """Particle state and properties of every particle entity, in entity order."""
    positions, velocities, masses, radii, groups = [], [], [], [], []
    start = 0
    for index, entity in enumerate(entities):
        if isinstance(entity, Particles):
            x = np.array(entity.positions, dtype=np.float64)
            count = x.shape[0]
            v = (
                np.zeros_like(x)
                if entity.velocities is None
                else np.array(entity.velocities, dtype=np.float64)
            )
        else:
            count = entity.count
            rng = np.random.default_rng(entity.seed)
            x = np.asarray(entity.center) + (rng.random((count, 3)) - 0.5) * np.asarray(entity.size)
            v = np.asarray(entity.velocity) + entity.velocity_jitter * rng.standard_normal(
                (count, 3)
            )
        positions.append(x)
        velocities.append(v)
        masses.append(np.broadcast_to(np.asarray(entity.mass, dtype=np.float64), (count,)))
        radii.append(np.broadcast_to(np.asarray(entity.radius, dtype=np.float64), (count,)))
        groups.append(ParticleGroup(entity.name or f"{entity.type}{index}", start, count))
        start += count

    def joined(arrays: list[np.ndarray], shape: tuple[int, ...]) -> np.ndarray:
        return frozen_array(np.concatenate(arrays) if arrays else np.zeros(shape))

    return (
        joined(positions, (0, 3)),
        joined(velocities, (0, 3)),
        joined(masses, (0,)),
        joined(radii, (0,)),
        tuple(groups),
    )
