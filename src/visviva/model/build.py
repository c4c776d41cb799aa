"""From a validated :class:`~visviva.model.scene.Scene` to the frozen :class:`Model`, over the
entity kinds.

Nothing here knows a kind: each entity is built by the hooks of its kind
(:mod:`visviva.entities`), in these steps —

1. *prepare*: what entities name is read in (mesh files), so everything after sees arrays;
2. *check*: what spans fields or entities (unique names, targets that exist, a run that is not
   too long, and each kind's own rules), every problem reported at once as a
   :class:`~visviva.errors.SceneError`;
3. *particles*: each particle-holding entity's count (the total checked before anything is
   allocated), then its rows, laid out in scene order as one block;
4. *build*: world gravity on every particle, then each entity's pieces in scene order, then
   each kind's ``finish`` in the registry's order; the handles' stage from the held particles;
5. *start*: the model's system is built and its first acceleration and energy evaluated, so a
   scene that ``visviva validate`` accepts also starts in ``visviva run``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .._compiling import watch_compiles
from .._registry import did_you_mean
from .._validation import describe
from ..entities import entity_kinds
from ..entities.checks import entity_names
from ..entities.context import BuildContext, Located, ParticleGroup, ParticleRows
from ..entities.fields import MAX_PARTICLES
from ..entities.system.build import OVERFLOW, located_parameter
from ..errors import ModelError, SceneError, SceneProblem
from ..forces import UniformGravity
from ..particles.handles import Handles
from .model import MAX_STEPS, Integration, Model, frozen_array
from .scene import Scene

__all__ = ["build_model", "entity_names"]

_NOT_FINITE = (
    "these values give a non-finite initial acceleration or energy (a mass, speed, length or "
    "position too large or too small to compute with, beyond ±1.8e308): use other values or units"
)


def build_model(scene: Scene, source: str | None = None) -> Model:
    """Check ``scene`` as a whole and build its :class:`Model`.

    Args:
        scene: A validated scene (from a file or a builder).
        source: The scene file's text, if it came from one (kept in recordings).

    Raises:
        SceneError: Listing every problem found.
    """
    watch_compiles()  # building and running a scene may compile its kernels: say so
    scene = prepared(scene)
    problems = _check(scene)
    if problems:
        raise SceneError(problems)
    settings = scene.integration
    context = BuildContext(scene, entity_names(scene), settings.dt / settings.substeps)
    try:
        _lay_out_particles(context)
        with np.errstate(all="ignore"):  # values that overflow are judged by the start check
            _build(context)
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
        particle_position=frozen_array(context.arrays["position"]),
        particle_velocity=frozen_array(context.arrays["velocity"]),
        particle_mass=frozen_array(context.arrays["mass"]),
        particle_radius=frozen_array(context.arrays["radius"]),
        particle_color=frozen_array(context.arrays["color"]),
        particle_alive=frozen_array(context.arrays["alive"], dtype=bool),
        particle_pinned=frozen_array(context.arrays["pinned"], dtype=bool),
        particle_groups=tuple(context.groups.values()),
        systems=tuple(context.systems),
        bodies=context.bodies,
        body_forces=tuple(context.body_forces),
        forces=tuple(context.forces),
        emitters=tuple(context.emitters),
        stages=tuple(sorted(context.stages, key=lambda stage: (stage.phase, stage.order))),
        contact_sources=tuple(context.contact_sources),
        edges=tuple(context.edges),
        faces=tuple(context.faces),
        recorded_once=context.static,
        recorded_attrs=context.attrs,
        output_formats=tuple(scene.output.formats),
        output_fps=scene.output.fps,
        output_speed=scene.output.speed,
        output_trail=scene.output.trail,
        output_color_by=scene.output.color_by,
        output_camera=None if scene.output.camera is None else scene.output.camera.text(),
        output_frame=scene.output.frame,
        output_style=scene.output.style,
        output_follow=scene.output.follow,
        source=source,
    )
    problems = _check_start(model)
    if problems:
        raise SceneError(problems)
    return model


def prepared(scene: Scene) -> Scene:
    """``scene`` with what its entities name read in (each kind's ``prepare``: mesh files);
    itself if there is nothing to read.

    Raises:
        SceneError: Listing every entity refused.
    """
    kinds = entity_kinds()
    entities, problems, changed = list(scene.entities), [], False
    for index, entity in enumerate(entities):
        prepare = kinds.get(entity.type).hooks.prepare
        if prepare is None:
            continue
        try:
            ready = prepare(entity, f"entities[{index}]")
        except SceneError as error:
            problems += error.problems
            continue
        changed |= ready is not entity
        entities[index] = ready
    if problems:
        raise SceneError(problems)
    return scene.model_copy(update={"entities": entities}) if changed else scene


def _check(scene: Scene) -> list[SceneProblem]:
    kinds = entity_kinds()
    problems: list[SceneProblem] = []
    entities = scene.entities
    if not any(kinds.get(e.type).holds_particles or kinds.get(e.type).state for e in entities):
        what = "nothing in this scene moves" if entities else "the scene is empty"
        moving = [k.name for k in kinds.values() if k.holds_particles or k.state]
        problems.append(
            SceneProblem(
                "entities",
                f"{what}; add at least one [[entities]] table of a type that moves: "
                + ", ".join(f'"{name}"' for name in moving),
            )
        )
    problems += _check_steps(scene)
    seen: dict[str, int] = {}
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
        check = kinds.get(entity.type).hooks.check
        if check is not None:
            problems += check(entity, where, scene)
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


def _lay_out_particles(context: BuildContext) -> None:
    """The particle block: every holding entity's rows in scene order (their count checked
    first: the rows of 50 million particles are 2.4 GB)."""
    kinds = entity_kinds()
    holders = []
    for index, entity in enumerate(context.scene.entities):
        hooks = kinds.get(entity.type).hooks
        if hooks.rows is not None:
            where = f"entities[{index}]"
            count = hooks.count(entity, where, context) if hooks.count is not None else None
            holders.append((index, where, entity, hooks, count))
    total = sum(count or 0 for *_, count in holders)
    if total > MAX_PARTICLES:
        raise Located(
            "entities",
            f"{total} particle slots in all (emitters count their capacity); the limit is "
            f"{MAX_PARTICLES} (about 2.4 GB of state)",
        )
    columns: dict[str, list[np.ndarray]] = {
        k: [] for k in ("position", "velocity", "mass", "radius", "color", "alive", "pinned")
    }
    start = 0
    for index, where, entity, hooks, _ in holders:
        assert hooks.rows is not None  # the holders are the kinds with rows
        rows: ParticleRows = hooks.rows(entity, where, context)
        count = rows.count
        columns["position"].append(np.asarray(rows.position, dtype=np.float64))
        columns["velocity"].append(np.asarray(rows.velocity, dtype=np.float64))
        for name, shape in (("mass", (count,)), ("radius", (count,)), ("color", (count, 3))):
            value = np.asarray(getattr(rows, name), dtype=np.float64)
            columns[name].append(np.broadcast_to(value, shape))
        columns["alive"].append(np.full(count, not rows.emitted))
        held = np.zeros(count, dtype=bool)
        held[np.asarray(rows.pinned, dtype=np.int64)] = True
        columns["pinned"].append(held)
        context.groups[index] = ParticleGroup(
            context.names[index], index, start, count, emitted=rows.emitted
        )
        context.data[index] = rows.data
        start += count
    empty = {"position": (0, 3), "velocity": (0, 3), "color": (0, 3)}
    context.arrays = {
        name: np.concatenate(parts) if parts else np.zeros(empty.get(name, (0,)))
        for name, parts in columns.items()
    }
    context.arrays["alive"] = context.arrays["alive"].astype(bool)
    context.arrays["pinned"] = context.arrays["pinned"].astype(bool)


def _build(context: BuildContext) -> None:
    """World gravity, each entity's pieces, each kind's finish, the springs after the other
    forces, then the handles' stage."""
    kinds = entity_kinds()
    if context.particle_count and context.gravity.any():
        context.forces.append(UniformGravity(context.scene.world.gravity, context.arrays["mass"]))
    for index, entity in enumerate(context.scene.entities):
        build = kinds.get(entity.type).hooks.build
        if build is not None:
            build(entity, f"entities[{index}]", context)
    for kind in kinds.values():
        finish = kind.hooks.finish
        entries = context.of_kind(kind.name)
        if finish is not None and entries:
            finish(entries, context)
    context.forces += context.springs
    if context.held:
        _hold(context)


def _hold(context: BuildContext) -> None:
    """The handles' stage; the held particles are pinned, and start where and as fast as their
    handles hold them at t = 0."""
    motions = [motion for motion, _ in context.held]
    particles = [indices for _, indices in context.held]
    arrays = context.arrays
    stage = Handles(motions, particles, [arrays["position"][p] for p in particles])
    arrays["position"][stage.indices], arrays["velocity"][stage.indices] = stage.place(0.0)
    arrays["pinned"][stage.indices] = True
    context.stages.append(stage)


def frame_problem(model: Model, frame: str) -> str | None:
    """What is wrong with framing ``frame`` (``"all"`` or a body's name) in ``model``'s
    videos, or ``None``."""
    bodies = () if model.bodies is None else model.bodies.names
    if frame == "all" or frame in bodies:
        return None
    shown = ", ".join(repr(name) for name in bodies[:20]) or "this scene has none"
    close = did_you_mean(frame, bodies)
    return f"frame {frame!r} is neither 'all' nor a body's name.{close} Bodies: {shown}"


def _check_start(model: Model) -> list[SceneProblem]:
    """Problems only the built model shows: a state that overflowed while being placed, or
    values that cannot give a finite start (``omega = 1e200`` squares to inf, a mass of 1e200
    at 10 m/s has an infinite kinetic energy).

    The model's system is built and its initial acceleration and energy are evaluated once, so
    a scene that ``visviva validate`` accepts also starts in ``visviva run``.
    """
    framing = frame_problem(model, model.output_frame)
    if framing is not None:
        return [SceneProblem("output.frame", framing)]
    followed = None if model.output_follow is None else frame_problem(model, model.output_follow)
    if followed is not None:
        return [SceneProblem("output.follow", "follow: " + followed.removeprefix("frame "))]
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
            results: list[Any] = [*system.derivative(start.t, start.parts)]
            results.append(np.asarray(system.energy(start)))
    except ModelError as error:
        return [located_parameter(str(error), where, values)]
    except (OverflowError, ZeroDivisionError, FloatingPointError, ValueError):
        return [SceneProblem(where, OVERFLOW)]
    if not all(np.isfinite(v).all() for v in results):
        return [SceneProblem(where, _NOT_FINITE)]
    return []
