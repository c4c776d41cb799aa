"""Entity kinds: each a folder of its own, found through one registry.

A scene is a list of entities, each with a ``type``: a *kind*. Every kind lives in one folder
here — its table (``schema.py``: the pydantic schema and the builder's typed method) and how it
is built (``build.py``: its hooks, :class:`~.kind.KindBuild`) — and is described by one
:class:`~.kind.EntityKind`. :data:`ENTITY_KINDS` is the only list of kinds: the scene's
validation, the builder, the model's build and the JSON schema go over it, so adding a kind is
a folder and its line here, in :data:`BUILT_IN` (with its builder method among
:class:`EntityMethods`' bases) — or, from a package of one's own, an entry point
(:mod:`.plugins`; ``docs/extending.md``).

The built-in kinds, in their order (which is the order their ``finish`` hooks run in):
particles, particle_cloud, rope, hair, springs, cloth, cloth_mesh, soft_lattice, soft_mesh,
body, emitter, system, force, collider, particle_collisions, body_contacts, boids, crowd.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

from .._lazy import lazy_names
from .._registry import Registry
from . import (
    body,
    body_contacts,
    boids,
    cloth,
    cloth_mesh,
    collider,
    crowd,
    emitter,
    force,
    hair,
    particle_cloud,
    particle_collisions,
    particles,
    rope,
    soft_lattice,
    soft_mesh,
    springs,
    system,
)
from .handles import Handle
from .kind import EntityKind, KindBuild, Replica

if TYPE_CHECKING:
    from .context import BuildContext, Located, ParticleGroup, ParticleRows
    from .contributions import force_kind, stage_kind

__all__ = [
    "BUILT_IN",
    "ENTITY_KINDS",
    "BuildContext",
    "EntityKind",
    "EntityMethods",
    "Handle",
    "KindBuild",
    "Located",
    "ParticleGroup",
    "ParticleRows",
    "Replica",
    "entity_kinds",
    "force_kind",
    "register_entity_kind",
    "stage_kind",
]

#: The kinds visviva ships, in registry order.
BUILT_IN: tuple[EntityKind, ...] = (
    particles.KIND,
    particle_cloud.KIND,
    rope.KIND,
    hair.KIND,
    springs.KIND,
    cloth.KIND,
    cloth_mesh.KIND,
    soft_lattice.KIND,
    soft_mesh.KIND,
    body.KIND,
    emitter.KIND,
    system.KIND,
    force.KIND,
    collider.KIND,
    particle_collisions.KIND,
    body_contacts.KIND,
    boids.KIND,
    crowd.KIND,
)


class EntityMethods(
    particles.ParticlesMethods,
    particle_cloud.ParticleCloudMethods,
    rope.RopeMethods,
    hair.HairMethods,
    springs.SpringGraphMethods,
    cloth.ClothMethods,
    cloth_mesh.ClothMeshMethods,
    soft_lattice.SoftLatticeMethods,
    soft_mesh.SoftMeshMethods,
    body.RigidBodyMethods,
    emitter.EmitterMethods,
    system.SystemMethods,
    force.ForceFieldMethods,
    collider.ColliderMethods,
    particle_collisions.ParticleCollisionMethods,
    body_contacts.BodyContactMethods,
    boids.BoidsMethods,
    crowd.CrowdMethods,
):
    """The built-in kinds' typed builder methods (:mod:`.methods`), which
    :class:`~visviva.model.SceneBuilder` has; a plugin's kind gets a method made from its
    schema instead."""


#: Every kind a scene may hold: the built-in ones, then those of installed plugins.
ENTITY_KINDS: Registry[EntityKind] = Registry("entity type")
for _kind in BUILT_IN:
    ENTITY_KINDS.register(_kind)

# What builds read and make loads on first use (visviva._lazy): the kinds' tables alone are
# what `visviva schema` reads, without NumPy.
__getattr__, __dir__ = lazy_names(
    __name__,
    __all__,
    {name: "context" for name in ("BuildContext", "Located", "ParticleGroup", "ParticleRows")}
    | {"force_kind": "contributions", "stage_kind": "contributions"},
)

_plugins_loaded = False
_plugins_lock = threading.Lock()


def entity_kinds() -> Registry[EntityKind]:
    """:data:`ENTITY_KINDS`, with the installed plugins' kinds loaded (once per process)."""
    global _plugins_loaded
    if not _plugins_loaded:
        with _plugins_lock:
            if not _plugins_loaded:
                from .plugins import load_plugins

                load_plugins(ENTITY_KINDS)
                _plugins_loaded = True
    return ENTITY_KINDS


def register_entity_kind(kind: EntityKind) -> EntityKind:
    """Register ``kind`` from Python (a plugin installed as a package is registered through
    its entry point instead): checked as a plugin's kind is, then usable in scenes and by
    the builder like the built-in kinds.

    Raises:
        ModelError: Saying why the kind is refused (a name already registered, a schema
            without its ``type``).
    """
    from .plugins import register_entity_kind as register

    return register(kind, entity_kinds())
