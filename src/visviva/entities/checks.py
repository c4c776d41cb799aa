"""Checks that span fields or entities, shared by the kinds' ``check`` hooks: lists that must
have one entry per particle, names that must name particle-holding entities.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from .._registry import did_you_mean
from ..errors import SceneProblem

__all__ = ["check_lengths", "check_names", "entity_names", "particle_holders"]


def entity_names(scene: Any) -> list[str]:
    """Each entity's name: its own, or its type and index (``particles0``, ``emitter2``)."""
    return [e.name or f"{e.type}{i}" for i, e in enumerate(scene.entities)]


def particle_holders(scene: Any) -> dict[str, Any]:
    """The entities that hold particles, by name, in scene order."""
    from . import entity_kinds

    kinds = entity_kinds()
    return {
        name: entity
        for name, entity in zip(entity_names(scene), scene.entities, strict=True)
        if kinds.get(entity.type).holds_particles
    }


def check_names(
    names: Sequence[str] | None, where: str, scene: Any, field: str = "targets"
) -> list[SceneProblem]:
    """A problem for each of ``names`` (the entity's ``field``) that names no entity holding
    particles, with the closest name and the valid ones."""
    if names is None:
        return []
    holders = particle_holders(scene)
    return [
        SceneProblem(
            f"{where}.{field}[{k}]",
            f"no particle entity is called {name!r}.{did_you_mean(name, holders)} Particle "
            f"entities: {', '.join(holders) or 'none'}",
        )
        for k, name in enumerate(names)
        if name not in holders
    ]


def check_lengths(entity: Any, where: str, count: int) -> list[SceneProblem]:
    """A problem for each of the entity's per-particle lists (``velocities``, ``mass``,
    ``radius``) that has not one entry per particle (``count``)."""
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
