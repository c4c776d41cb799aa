"""What an entity kind is: its table in scene files, its builder method and how it is built.

A kind (``"cloth"``, ``"collider"``, a user's ``"magnet"``) is described once, by an
:class:`EntityKind`: the name scene files give it as their ``type``, the pydantic schema of its
table (every field with its default, unit and one home), the builder methods that mirror the
schema, and the module that builds it. The build module is imported only when a scene that holds
the kind is built, so that reading a scene's schema (``visviva schema``) costs no physics.

The build module holds one :class:`KindBuild`: the hooks the model's build calls, each ``None``
if the kind does not need it:

* ``prepare(entity, where)``: the entity with what it names read in (a mesh file's vertices),
  when it is added to a builder and before a scene is built;
* ``check(entity, where, scene)``: what only the whole scene shows (targets that hold no
  particles, two flocks of one particle), as a list of problems;
* ``count(entity, where, context)`` and ``rows(entity, where, context)``: how many particles
  the entity holds (cheap: the scene's total is checked before anything is allocated), then
  the particles themselves, appended to the scene's particle block in scene order
  (:class:`~.context.ParticleRows`);
* ``build(entity, where, context)``: what the entity adds to the model once every particle has
  its slot: forces, stages, held particles, systems, drawings (:class:`~.context.BuildContext`);
* ``finish(entries, context)``: once for the whole kind, after every entity was built, with its
  ``(where, entity)`` entries in scene order: pieces made of all of them at once (the colliders'
  one collision stage, the rigid bodies);
* ``replica(entity)``: how the entity is copied when the runs of a sweep advance as one model
  (:class:`Replica`; :mod:`visviva.model.replicas`), or ``None`` if it keeps its scene from
  having replicas (it couples particles, or has state of its own).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

if TYPE_CHECKING:
    from ..errors import SceneProblem
    from .context import BuildContext, ParticleRows

__all__ = ["HOLDS", "EntityKind", "KindBuild", "Replica"]

#: ``prepare(entity, where)``: the entity with the files it names read.
Prepare = Callable[[Any, str], Any]
#: ``check(entity, where, scene)``: the problems only the whole scene shows.
Check = Callable[[Any, str, Any], "list[SceneProblem]"]
#: ``count(entity, where, context)``: how many particles an entity holds.
Count = Callable[[Any, str, "BuildContext"], int]
#: ``rows(entity, where, context)``: the particles an entity holds.
Rows = Callable[[Any, str, "BuildContext"], "ParticleRows"]
#: ``build(entity, where, context)``: what one entity adds to the model.
Build = Callable[[Any, str, "BuildContext"], None]
#: ``finish(entries, context)``: what the kind's entities add together.
Finish = Callable[["Sequence[tuple[str, Any]]", "BuildContext"], None]


@dataclass(frozen=True)
class Replica:
    """How an entity is copied into a model that holds many runs of its scene.

    Attributes:
        holds: Its particles are copied for each run (a run's particles are one span).
        room: The room a copy of it takes in the merged model: ``"impulse"`` or ``"penalty"``
            colliders, ``"law"`` fields; ``None`` for none.
        folds: It takes no room when every run has the same values and it acts on every
            particle (a field the compiled step folds into one acceleration).
    """

    holds: bool = False
    room: str | None = None
    folds: bool = False


#: The replica of an entity whose particles are copied for each run.
HOLDS = Replica(holds=True)
#: ``replica(entity)``: how an entity is copied into a model of many runs, or ``None``.
Replicate = Callable[[Any], "Replica | None"]


@dataclass(frozen=True)
class KindBuild:
    """The hooks of a kind's build module (see the module docstring); ``None``: not needed."""

    prepare: Prepare | None = None
    check: Check | None = None
    count: Count | None = None
    rows: Rows | None = None
    build: Build | None = None
    finish: Finish | None = None
    replica: Replicate | None = None


@dataclass(frozen=True, eq=False)
class EntityKind:
    """One kind of scene entity.

    Args:
        name: Its ``type`` in scene files (``"cloth"``); the builder's method is
            ``add_<name>``.
        schema: The pydantic model of its table, with ``type: Literal[name]``.
        summary: What it is, in a line (``visviva schema``, messages).
        build: The dotted name of the module that holds its :class:`KindBuild` as ``BUILD``
            (imported on first use), or the :class:`KindBuild` itself.
        holds_particles: True if its entities hold particles, which forces, colliders and
            behaviours may target by the entity's name.
        state: True if its entities have state of their own in the integrated arrays (rigid
            bodies, named systems' coordinates).
        renamed: Field names it gave up, and their replacements: a scene that still uses one
            is refused with the new name.
    """

    name: str
    schema: type[BaseModel]
    summary: str
    build: str | KindBuild
    holds_particles: bool = False
    state: bool = False
    renamed: Mapping[str, str] = field(default_factory=lambda: MappingProxyType({}))

    @cached_property
    def hooks(self) -> KindBuild:
        """The kind's :class:`KindBuild` (from its build module)."""
        if isinstance(self.build, KindBuild):
            return self.build
        hooks = importlib.import_module(self.build).BUILD
        if not isinstance(hooks, KindBuild):
            raise TypeError(f"{self.build}.BUILD must be a KindBuild, not {type(hooks).__name__}")
        return hooks
