"""The particle–particle collisions of a scene: their check and their stage (:mod:`.build` calls
both; the entity is :mod:`.scene_contacts`, the stage :mod:`visviva.collision.particle_contacts`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..collision.particle_contacts import ParticleContacts
from ..errors import ModelError, SceneProblem
from ..geometry.neighbour_grid import NeighbourGrid
from .model import ParticleGroup
from .parts import Located, _targets
from .scene import Scene
from .scene_contacts import ParticleCollisionSettings

__all__ = ["check_contacts", "contact_stages"]


def check_contacts(scene: Scene) -> list[SceneProblem]:
    """A scene holds at most one ``particle_collisions`` entity (it says how every pair of its
    targets collides; two would disagree about the pairs they share)."""
    chosen = [i for i, e in enumerate(scene.entities) if isinstance(e, ParticleCollisionSettings)]
    return [
        SceneProblem(
            f"entities[{index}]",
            f"a scene holds at most one particle_collisions entity; entities[{chosen[0]}] is "
            "one already: merge their `targets` into it",
        )
        for index in chosen[1:]
    ]


def contact_stages(
    scene: Scene,
    groups: Sequence[ParticleGroup],
    arrays: dict[str, np.ndarray],
    colliders: Any,
    h: float,
) -> list[ParticleContacts]:
    """The particle–particle contact stage (a list of at most one), over the particles'
    ``arrays`` (``mass``, ``pinned``: pinned particles are of infinite mass), with the impulse
    colliders' stage ``colliders`` (or ``None``) in the same solve; ``h`` [s] is the
    integrator step (a contact rests below the speed gravity gives in two)."""
    stages = []
    count = arrays["mass"].shape[0]
    for index, entity in enumerate(scene.entities):
        if not isinstance(entity, ParticleCollisionSettings) or not count:
            continue
        inverse = np.where(arrays["pinned"], 0.0, 1.0 / arrays["mass"])
        mask = np.zeros(count, dtype=np.bool_)
        mask[_targets(entity, groups, count).indices] = True  # type: ignore[arg-type]
        resting = entity.resting_speed
        if resting is None:
            resting = 2.0 * math.hypot(*scene.world.gravity) * h  # Mirtich & Canny 1995
        try:
            stages.append(
                ParticleContacts(
                    inverse,
                    mask,
                    restitution=entity.restitution,
                    friction=entity.friction,
                    iterations=entity.iterations,
                    resting_speed=resting,
                    gravity=scene.world.gravity,
                    colliders=colliders,
                )
            )
        except ModelError as error:
            raise Located(f"entities[{index}]", str(error)) from None
        _check_reach(arrays, mask, index)
    return stages


def _check_reach(arrays: dict[str, np.ndarray], mask: np.ndarray, index: int) -> None:
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
        raise Located(f"entities[{index}]", f"particle collisions: {error}") from None
