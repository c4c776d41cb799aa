"""How a ``particle_collisions`` entity is built: the sphere–sphere contact stage over its
targets (:class:`~visviva.collision.particle_contacts.ParticleContacts`), with the scene's
impulse colliders in the same solve. A scene holds at most one."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...collision import ParticleCollisions
from ...collision.particle_contacts import ParticleContacts
from ...errors import ModelError, SceneProblem
from ...geometry.neighbour_grid import NeighbourGrid
from ..checks import check_names
from ..context import BuildContext, Located
from ..kind import KindBuild
from .schema import ParticleCollisionSettings

__all__ = ["BUILD"]


def _check(entity: ParticleCollisionSettings, where: str, scene: Any) -> list[SceneProblem]:
    """Targets that hold particles, and no other ``particle_collisions`` entity before this
    one (it says how every pair of its targets collides; two would disagree about the pairs
    they share)."""
    problems = check_names(entity.targets, where, scene)
    first = next(i for i, e in enumerate(scene.entities) if e.type == "particle_collisions")
    if f"entities[{first}]" != where:
        problems.append(
            SceneProblem(
                where,
                f"a scene holds at most one particle_collisions entity; entities[{first}] is one "
                "already: merge their `targets` into it",
            )
        )
    return problems


def _finish(
    entries: Sequence[tuple[str, ParticleCollisionSettings]], context: BuildContext
) -> None:
    """The contact stage, once the colliders' collision stage exists (the collider kind
    finishes first)."""
    where, entity = entries[0]
    count = context.particle_count
    if not count:
        return
    arrays = context.arrays
    inverse = np.where(arrays["pinned"], 0.0, 1.0 / arrays["mass"])
    mask = np.zeros(count, dtype=np.bool_)
    mask[context.targets(entity.targets).indices] = True
    resting = entity.resting_speed
    if resting is None:
        resting = 2.0 * math.hypot(*context.gravity) * context.h  # Mirtich & Canny 1995
    colliders = next((s for s in context.stages if isinstance(s, ParticleCollisions)), None)
    try:
        stage = ParticleContacts(
            inverse,
            mask,
            restitution=entity.restitution,
            friction=entity.friction,
            iterations=entity.iterations,
            resting_speed=resting,
            gravity=context.scene.world.gravity,
            colliders=colliders,
        )
    except ModelError as error:
        raise Located(where, str(error)) from None
    _check_reach(arrays, mask, where)
    context.stages.append(stage)


def _check_reach(arrays: dict[str, np.ndarray], mask: np.ndarray, where: str) -> None:
    """The colliding spheres start within the neighbour grid's reach of the origin (2⁴⁰ cells
    of a diameter, up to 10¹⁵⁰ m): binned once now so that a scene placing them beyond is
    refused before it runs (a sphere that flies beyond it stops the run with an explanation)."""
    live = mask & arrays["alive"]
    largest = float(arrays["radius"][live].max(initial=0.0))
    if largest == 0.0:
        return
    try:
        NeighbourGrid(2.0 * largest).update(arrays["position"], live)
    except ModelError as error:
        raise Located(where, f"particle collisions: {error}") from None


BUILD = KindBuild(check=_check, finish=_finish)
