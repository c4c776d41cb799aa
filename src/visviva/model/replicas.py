"""Replicas: the members of an ensemble of particle scenes as one model, stepped as one.

The runs of a sweep over a particle scene — a ball dropped with fifty restitutions, a rope
with fifty stiffnesses — hold the same entities with different values. :meth:`Replicas.of`
builds one model that holds every member's particles, so that one step of it advances them
all (one pass of each compiled kernel instead of one per member, and no process per member):

* each member's particle entities (particles, clouds, ropes, hair, spring networks, cloths, soft
  bodies) are copied in, renamed apart, member after member: member ``k``'s particles are one
  contiguous range (its *span*), in the order of its own run;
* a force or collider with the same values in every member is kept once and acts on every
  member's copy of its targets; one whose values differ is copied for each member and acts on
  that member's particles only, in the same place among the forces and colliders;
* the springs of every body become one set (one force, summed spring by spring).

Nothing couples the members: a force field acts on each particle from its own state, springs
join particles of one body, and colliders are static. Each particle therefore sees the forces
and colliders of its own run, in the same order, and moves as it would alone — to round-off:
where a member's run sums a field or a contact by another path than the merged model does (a
field folded into the compiled step alone but evaluated by its law here, a cloth's springs by
its lattice's stencil alone), the last bits may differ. Scenes with anything that couples
particles (gravitation, particle collisions, flocks, crowds) or that is not particles
(emitters, named systems, rigid bodies) have no replicas: :func:`replica_key` is ``None``.
Which entities are copied, and the room their copies take, each kind says
(:class:`~visviva.entities.kind.Replica`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Hashable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..collision.colliders import MAX_COLLIDERS
from ..entities import entity_kinds
from ..entities.kind import Replica
from ..errors import ModelError
from ..forces.springs import Springs
from ..ode.state import Layout, State
from ..particles.fused import MAX_LAW_FIELDS
from .build import build_model, entity_names
from .model import Model
from .scene import Scene
from .scene_system import layout

__all__ = ["Replicas", "replica_capacity", "replica_key"]


def _replica(entity: Any) -> Replica | None:
    """How ``entity`` is copied, as its kind says (``None``: no replicas)."""
    replicate = entity_kinds().get(entity.type).hooks.replica
    return None if replicate is None else replicate(entity)


def replica_key(scene: Scene) -> Hashable | None:
    """What scenes must share to be replicas of one another: their world, time stepping and
    entities (types, names, targets), their values aside; ``None`` if ``scene`` has an entity
    its kind does not replicate (see the module docstring)."""
    structure = []
    replicas = [_replica(entity) for entity in scene.entities]
    if any(r is None for r in replicas) or not any(r.holds for r in replicas if r is not None):
        return None
    for entity in scene.entities:
        targets = getattr(entity, "targets", None)
        structure.append((entity.type, entity.name, None if targets is None else tuple(targets)))
    settings = scene.integration.model_dump(exclude={"energy_tolerance"})
    return (scene.world.model_dump_json(), tuple(sorted(settings.items())), tuple(structure))


def replica_capacity(scenes: Sequence[Scene]) -> int:
    """How many of these replicas (one :func:`replica_key`) one model may hold: each member
    adds a copy of every collider and field whose values differ between members, and a model
    has room for :data:`~visviva.collision.colliders.MAX_COLLIDERS` colliders of each
    response and :data:`~visviva.particles.fused.MAX_LAW_FIELDS` fields that are not folded
    into the compiled step."""
    first = scenes[0]
    shared = {"impulse": 0, "penalty": 0, "law": 0}
    copied = dict.fromkeys(shared, 0)
    for j, entity in enumerate(first.entities):
        replica = _replica(entity)
        if replica is None or replica.room is None:
            continue
        alone = _same(scenes, j)
        if alone and entity.targets is None and replica.folds:
            continue
        (shared if alone else copied)[replica.room] += 1
    room = {"impulse": MAX_COLLIDERS, "penalty": MAX_COLLIDERS, "law": MAX_LAW_FIELDS}
    return min(
        [len(scenes)]
        + [(room[kind] - shared[kind]) // copied[kind] for kind in room if copied[kind]]
    )


@dataclass(frozen=True, eq=False)
class Replicas:
    """Members' models as one (see the module docstring).

    Attributes:
        model: The model holding every member.
        members: The members' own models.
        spans: Each member's particles in :attr:`model`: ``(first, count)``.
        layouts: Each member's state layout.
    """

    model: Model
    members: tuple[Model, ...]
    spans: tuple[tuple[int, int], ...]
    layouts: tuple[Layout, ...]

    @classmethod
    def of(cls, members: Sequence[Model]) -> Replicas:
        """The replicas of ``members``.

        Raises:
            ModelError: Members that are not replicas of one another, or more than
                :func:`replica_capacity` allows.
        """
        scenes = [m.scene for m in members]
        key = replica_key(scenes[0])
        if key is None or any(replica_key(s) != key for s in scenes[1:]):
            raise ModelError(
                "these models are not replicas of one another: each must hold only particles, "
                "force fields (no gravitation) and colliders, with the same entities, world and "
                "integration settings"
            )
        if len(scenes) > replica_capacity(scenes):
            raise ModelError(
                f"{len(scenes)} replicas exceed the {replica_capacity(scenes)} one model can "
                "hold (a collider or field whose values differ is copied for each member)"
            )
        names = entity_names(scenes[0])
        merged = build_model(_merged_scene(scenes, names))
        groups = {g.name: g for g in merged.particle_groups}
        spans = []
        for k in range(len(scenes)):
            mine = [
                groups[_member(name, k)]
                for name, entity in zip(names, scenes[0].entities, strict=True)
                if _holds(entity)
            ]
            spans.append((mine[0].start, sum(g.count for g in mine)))
        springs = [f for f in merged.forces if isinstance(f, Springs)]
        if len(springs) > 1 or any(f.stencil is not None for f in springs):
            others = [f for f in merged.forces if not isinstance(f, Springs)]
            merged = dataclasses.replace(merged, forces=(*others, _one_set(springs, merged)))
        layouts = tuple(layout(m) for m in members)
        return cls(merged, tuple(members), tuple(spans), layouts)

    def member_state(self, state: State, k: int) -> State:
        """Member ``k``'s own state (its layout, its arrays copied) from ``state`` of
        :attr:`model`."""
        first, count = self.spans[k]
        rows = slice(3 * first, 3 * (first + count))

        def cut(arrays: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
            return tuple(np.array(a[rows]) for a in arrays)

        carried = {
            name: np.array(value[first : first + count]) for name, value in state.carried.items()
        }
        derivative = None if state.derivative is None else cut(state.derivative)
        return State(state.t, cut(state.parts), self.layouts[k], carried, derivative)

    def join(self, states: Sequence[State]) -> State:
        """The state of :attr:`model` whose members are ``states`` (one per member, at one
        time)."""

        def joined(arrays: Sequence[tuple[np.ndarray, ...]]) -> tuple[np.ndarray, ...]:
            return tuple(np.concatenate(parts) for parts in zip(*arrays, strict=True))

        derivatives = [s.derivative for s in states]
        derivative = None
        if all(d is not None for d in derivatives):
            derivative = joined(derivatives)  # type: ignore[arg-type]
        carried = {
            name: np.concatenate([s.carried[name] for s in states]) for name in states[0].carried
        }
        parts = joined([s.parts for s in states])
        return State(states[0].t, parts, layout(self.model), carried, derivative)

    def member_of(self, particle: int) -> int:
        """The member whose span holds ``particle`` (an index into :attr:`model`'s)."""
        firsts = [first for first, _ in self.spans]
        return int(np.searchsorted(firsts, particle, side="right")) - 1


def _holds(entity: Any) -> bool:
    replica = _replica(entity)
    return replica is not None and replica.holds


def _member(name: str, k: int) -> str:
    """An entity's name in the merged scene: the member's copy."""
    return f"{name} (member {k})"


def _same(scenes: Sequence[Scene], j: int) -> bool:
    """True if entity ``j`` has the same values in every scene (as written: −0.0 is not 0.0)."""
    text = scenes[0].entities[j].model_dump_json()
    return all(s.entities[j].model_dump_json() == text for s in scenes[1:])


def _merged_scene(scenes: Sequence[Scene], names: list[str]) -> Scene:
    """One scene holding every member (see the module docstring)."""
    first = scenes[0]
    holders = [n for n, e in zip(names, first.entities, strict=True) if _holds(e)]
    entities: list[Any] = [
        entity.model_copy(update={"name": _member(name, k)})
        for k, scene in enumerate(scenes)
        for name, entity in zip(names, scene.entities, strict=True)
        if _holds(entity)
    ]
    for j, (name, entity) in enumerate(zip(names, first.entities, strict=True)):
        if _holds(entity):
            continue
        targets = holders if entity.targets is None else entity.targets
        if _same(scenes, j):
            every = [_member(t, k) for k in range(len(scenes)) for t in targets]
            entities.append(entity.model_copy(update={"targets": every}))
            continue
        for k, scene in enumerate(scenes):
            copy = scene.entities[j].model_copy(
                update={"name": _member(name, k), "targets": [_member(t, k) for t in targets]}
            )
            entities.append(copy)
    return first.model_copy(update={"entities": entities})


def _one_set(springs: list[Springs], model: Model) -> Springs:
    """Every body's springs as one force, summed spring by spring (no lattice stencil)."""
    return Springs(
        np.concatenate([f.pairs for f in springs]),
        np.concatenate([f.rest_length for f in springs]),
        np.concatenate([f.stiffness for f in springs]),
        np.concatenate([f.damping for f in springs]),
        model.particle_count,
    )
