"""The flocks of a scene: their cross-entity checks and their stages (:mod:`.build` calls both).

A flock's boids are the particles of its ``targets``; it follows the particles of its
``leader`` entity, and avoids every collider that acts on its boids (a collider without
``targets``, or one naming one of the flock's targets), whatever the collider's response.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .._registry import did_you_mean
from ..errors import ModelError, SceneProblem
from ..geometry.neighbour_grid import NeighbourGrid
from ..particles.boids import Boids
from .model import ParticleGroup
from .parts import Located, _shape
from .scene import Collider, Scene
from .scene_boids import Boids as BoidsEntity

__all__ = ["boids_stages", "check_flocks"]


def check_flocks(scene: Scene, holders: Sequence[str]) -> list[SceneProblem]:
    """Each flock's ``leader`` names a particle entity (one of ``holders``) that is not one
    of its targets, and no particle entity is the target of two flocks (targets themselves
    are checked with every behaviour's, in :mod:`.build`)."""
    problems = []
    flocked: dict[str, int] = {}
    for index, entity in enumerate(scene.entities):
        if not isinstance(entity, BoidsEntity):
            continue
        where = f"entities[{index}]"
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
        for k, target in enumerate(entity.targets):
            if target in flocked and flocked[target] != index:
                problems.append(
                    SceneProblem(
                        f"{where}.targets[{k}]",
                        f"{target!r} is already a target of the flock entities[{flocked[target]}]"
                        ": a particle belongs to one flock",
                    )
                )
            flocked.setdefault(target, index)
    return problems


def boids_stages(
    scene: Scene, groups: Sequence[ParticleGroup], arrays: dict[str, np.ndarray]
) -> list[Boids]:
    """The stage of each flock, in scene order, its boids binned once at their start
    positions (``arrays``' ``position`` and ``alive``) so that a flock beyond the grid's reach
    is refused now.

    Raises:
        Located: A value the stage refuses, at the field it names.
    """
    from ..collision import ColliderSet

    by_name = {g.name: g for g in groups}
    stages = []
    for index, entity in enumerate(scene.entities):
        if not isinstance(entity, BoidsEntity):
            continue
        where = f"entities[{index}]"
        rows = _rows([by_name[t] for t in entity.targets])
        leaders = None if entity.leader is None else _rows([by_name[entity.leader]])
        chosen = [
            (i, e)
            for i, e in enumerate(scene.entities)
            if isinstance(e, Collider)
            and (e.targets is None or any(t in e.targets for t in entity.targets))
        ]
        chosen.sort(key=lambda pair: pair[1].shape != "plane")  # planes first
        colliders = ColliderSet([_shape(e, f"entities[{i}]") for i, e in chosen])
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
                name=entity.name or f"boids{index}",
            )
            # The boids must start within the neighbour grid's reach of the origin.
            NeighbourGrid(stage.radius).update(arrays["position"][rows], arrays["alive"][rows])
        except ModelError as error:
            raise _at_field(where, str(error)) from None
        stages.append(stage)
    return stages


def _weight(weight: float | None, what: object) -> float:
    """A goal's or leader's weight: 1/s by default when the goal or leader is given."""
    if weight is not None:
        return weight
    return 0.0 if what is None else 1.0


def _rows(chosen: Sequence[ParticleGroup]) -> np.ndarray:
    parts = [np.arange(g.start, g.start + g.count, dtype=np.int64) for g in chosen]
    return np.concatenate(parts) if parts else np.zeros(0, dtype=np.int64)


def _at_field(where: str, message: str) -> Located:
    """A refusal located at the field its message names in backquotes (else the entity)."""
    if message.startswith("`") and message.count("`") >= 2:
        field = message[1:].split("`", 1)[0]
        if field in BoidsEntity.model_fields:
            return Located(f"{where}.{field}", message)
    return Located(where, message)
