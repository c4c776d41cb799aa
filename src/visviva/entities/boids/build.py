"""How a ``boids`` entity is built: its flock's stage (:class:`~visviva.particles.boids.Boids`),
after the checks only the whole scene shows.

A flock's boids are the particles of its ``targets``; it follows the particles of its
``leader`` entity, and avoids every collider that acts on its boids (a collider without
``targets``, or one naming one of the flock's targets), whatever the collider's response.
"""

from __future__ import annotations

from typing import Any

from ..._registry import did_you_mean
from ...collision import ColliderSet
from ...errors import ModelError, SceneProblem
from ...geometry.neighbour_grid import NeighbourGrid
from ...particles.boids import Boids
from ..checks import check_names, particle_holders
from ..collider.shapes import collider_shape
from ..context import BuildContext, Located
from ..kind import KindBuild
from .schema import Boids as BoidsEntity

__all__ = ["BUILD"]


def _check(entity: BoidsEntity, where: str, scene: Any) -> list[SceneProblem]:
    """Its targets hold particles; its ``leader`` names a particle entity that is not one of
    its targets; no particle entity is the target of an earlier flock too."""
    problems = check_names(entity.targets, where, scene)
    holders = particle_holders(scene)
    leader = entity.leader
    if leader is not None and leader not in holders:
        problems.append(
            SceneProblem(
                f"{where}.leader",
                f"no particle entity is called {leader!r}.{did_you_mean(leader, holders)} "
                f"Particle entities: {', '.join(holders) or 'none'}",
            )
        )
    elif leader is not None and leader in entity.targets:
        problems.append(
            SceneProblem(
                f"{where}.leader",
                f"{leader!r} is also one of the flock's targets: a flock does not steer its "
                "leader; name another entity, or take it out of `targets`",
            )
        )
    flocked: dict[str, str] = {}
    for index, other in enumerate(scene.entities):
        if f"entities[{index}]" == where:
            break
        if other.type == "boids":
            for target in other.targets:
                flocked.setdefault(target, f"entities[{index}]")
    for k, target in enumerate(entity.targets):
        if target in flocked:
            problems.append(
                SceneProblem(
                    f"{where}.targets[{k}]",
                    f"{target!r} is already a target of the flock {flocked[target]}: a particle "
                    "belongs to one flock",
                )
            )
    return problems


def _build(entity: BoidsEntity, where: str, context: BuildContext) -> None:
    """The flock's stage, its boids binned once at their start positions so that a flock
    beyond the grid's reach is refused now.

    Raises:
        Located: A value the stage refuses, at the field it names.
    """
    rows = context.particles_of(entity.targets)
    leaders = None if entity.leader is None else context.particles_of([entity.leader])
    chosen = [
        (w, e)
        for w, e in context.of_kind("collider")
        if e.targets is None or any(t in e.targets for t in entity.targets)
    ]
    chosen.sort(key=lambda pair: pair[1].shape != "plane")  # planes first
    colliders = ColliderSet([collider_shape(e, w) for w, e in chosen])
    arrays = context.arrays
    try:
        stage = Boids(
            rows,
            radius=entity.radius,
            separation=entity.separation,
            max_speed=entity.max_speed,
            max_acceleration=entity.max_acceleration,
            fov_deg=entity.fov_deg,
            min_speed=entity.min_speed,
            separation_weight=entity.separation_weight,
            alignment_weight=entity.alignment_weight,
            cohesion_weight=entity.cohesion_weight,
            goal=entity.goal,
            goal_weight=_weight(entity.goal_weight, entity.goal),
            leaders=leaders,
            leader_weight=_weight(entity.leader_weight, entity.leader),
            colliders=colliders,
            look_ahead=entity.look_ahead,
            min_distance=entity.min_distance,
            plane=entity.plane,
            name=context.names[context.index(where)],
        )
        # The boids must start within the neighbour grid's reach of the origin.
        NeighbourGrid(stage.radius).update(arrays["position"][rows], arrays["alive"][rows])
    except ModelError as error:
        raise _at_field(where, str(error)) from None
    context.stages.append(stage)


def _weight(weight: float | None, what: object) -> float:
    """A goal's or leader's weight: 1/s by default when the goal or leader is given."""
    if weight is not None:
        return weight
    return 0.0 if what is None else 1.0


def _at_field(where: str, message: str) -> Located:
    """A refusal located at the field its message names in backquotes (else the entity)."""
    if message.startswith("`") and message.count("`") >= 2:
        field = message[1:].split("`", 1)[0]
        if field in BoidsEntity.model_fields:
            return Located(f"{where}.{field}", message)
    return Located(where, message)


BUILD = KindBuild(check=_check, build=_build)
