"""How ``collider`` entities are built: all of one response together — the impulse colliders
one collision stage (:class:`~visviva.collision.ParticleCollisions`), the penalty colliders one
force (:class:`~visviva.collision.PenaltyContact`) — each reporting its contacts, and the
drawable ones recorded as scenery (:mod:`.outputs`).

A collider meets the particles of its ``targets`` (every particle by default), planes first in
the collider set (the kernels' fast path). Pinned particles meet none (nothing moves them), nor
do particles that another kind exempts (a crowd's agents meet its walls through the crowd's
forces only: :attr:`~visviva.entities.context.BuildContext.exempt`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...collision import (
    MAX_COLLIDERS,
    ColliderResponse,
    ColliderSet,
    ParticleCollisions,
    PenaltyContact,
)
from ...errors import SceneProblem
from ..checks import check_names
from ..context import BuildContext, Located
from ..kind import KindBuild, Replica
from .outputs import scenery_attrs, scenery_fields, wall_fields
from .schema import Collider
from .shapes import collider_shape

__all__ = ["BUILD"]


def _check(entity: Collider, where: str, scene: Any) -> list[SceneProblem]:
    return check_names(entity.targets, where, scene)


def _finish(entries: Sequence[tuple[str, Collider]], context: BuildContext) -> None:
    impulse = _chosen(entries, "impulse")
    if impulse and context.particle_count:
        if len(impulse) > MAX_COLLIDERS:
            raise Located(
                impulse[MAX_COLLIDERS][0],
                f"a scene may hold at most {MAX_COLLIDERS} impulse colliders",
            )
        masks = _masks(impulse, context)
        if masks.any():  # some particle meets them (not only pinned ones, or a crowd's walls)
            response = ColliderResponse(
                restitution=[e.restitution for _, e in impulse],
                friction=[e.friction for _, e in impulse],
                resting_speed=_resting_speeds(impulse, context),
                time_of_impact=[e.time_of_impact for _, e in impulse],
            )
            stage = ParticleCollisions(_set(impulse), response, masks, _labels(impulse, context))
            context.stages.append(stage)
            context.contact_sources.append(stage)
    penalty = _chosen(entries, "penalty")
    if penalty and context.particle_count:
        masks = _masks(penalty, context)
        if masks.any():
            force = PenaltyContact(
                _set(penalty),
                stiffness=[e.stiffness for _, e in penalty],  # type: ignore[misc]
                damping=[e.damping or 0.0 for _, e in penalty],
                masks=masks,
                radius=context.arrays["radius"],
                labels=_labels(penalty, context),
                resting_speed=_resting_speeds(penalty, context),
            )
            context.forces.append(force)
            context.contact_sources.append(force)
    context.static |= scenery_fields(entries) | wall_fields(entries)
    context.attrs |= scenery_attrs(entries)


def _chosen(entries: Sequence[tuple[str, Collider]], response: str) -> list[tuple[str, Collider]]:
    """The colliders of one response, planes first (the kernels' fast path; see
    :class:`~visviva.collision.ColliderSet`)."""
    chosen = [(where, e) for where, e in entries if e.response == response]
    return sorted(chosen, key=lambda pair: pair[1].shape != "plane")


def _set(chosen: Sequence[tuple[str, Collider]]) -> ColliderSet:
    return ColliderSet([collider_shape(e, where) for where, e in chosen])


def _masks(chosen: Sequence[tuple[str, Collider]], context: BuildContext) -> np.ndarray:
    """Bit ``k`` of ``masks[i]`` set where particle ``i`` meets collider ``k``."""
    masks = np.zeros(context.particle_count, dtype=np.uint64)
    for bit, (_, e) in enumerate(chosen):
        masks[context.targets(e.targets).indices] |= np.uint64(1) << np.uint64(bit)
    for particles, colliders in context.exempt:
        for bit, (where, _) in enumerate(chosen):
            if context.index(where) in colliders:
                masks[particles] &= ~(np.uint64(1) << np.uint64(bit))
    masks[context.arrays["pinned"]] = 0
    return masks


def _resting_speeds(chosen: Sequence[tuple[str, Collider]], context: BuildContext) -> list[float]:
    """Each collider's resting speed [m/s]: by default, the speed gravity gives in two steps
    of ``h`` (Mirtich & Canny 1995)."""
    gravity = math.hypot(*context.gravity)  # no overflow for huge components
    resting = 2.0 * gravity * context.h
    return [resting if e.resting_speed is None else e.resting_speed for _, e in chosen]


def _labels(chosen: Sequence[tuple[str, Collider]], context: BuildContext) -> list[str]:
    """Each collider's name, or where it is in the scene."""
    return [e.name or where for where, e in chosen]


BUILD = KindBuild(
    check=_check, finish=_finish, replica=lambda entity: Replica(room=entity.response)
)
