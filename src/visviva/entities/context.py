"""What an entity kind reads and adds to while a model is built.

The model's build (:func:`visviva.model.build.build_model`) goes over the scene twice. First
every entity that holds particles gives its rows (:class:`ParticleRows`), which are laid out
in scene order as one particle block (:class:`ParticleGroup` says which slots are whose).
Then every entity adds its pieces to the :class:`BuildContext` — forces, stages, held
particles, systems, rigid bodies, drawings — and each kind finishes what its entities make
together. The model is made from what the context then holds; the context is dropped.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import SceneProblem
from ..forces.base import Targets

if TYPE_CHECKING:
    from ..collision.contact_classes import ContactSource
    from ..forces.base import Force
    from ..forces.body_forces import BodyForce
    from ..forces.springs import Springs
    from ..ode.stage import Stage
    from ..particles.emitters import EmitterSpec
    from ..particles.handles import HandleMotion
    from ..rigid.bodies import RigidBodies
    from .system.block import SystemInstance

__all__ = ["BuildContext", "Located", "ParticleGroup", "ParticleRows"]


class Located(Exception):
    """A refusal of an entity's values, located at the entity (``entities[i]...``)."""

    def __init__(self, where: str, message: str) -> None:
        super().__init__(message)
        self.problem = SceneProblem(where, message)


@dataclass(frozen=True)
class ParticleGroup:
    """A named range of particle slots that came from one scene entity.

    Attributes:
        name: Entity name.
        entity: The entity's index in the scene.
        start: First particle index.
        count: Number of particles (an emitter's capacity).
        emitted: True for an emitter's slots, whose particles are born and die.
    """

    name: str
    entity: int
    start: int
    count: int
    emitted: bool = False

    @property
    def indices(self) -> np.ndarray:
        """Its particle indices, ``(count,)``."""
        return np.arange(self.start, self.start + self.count, dtype=np.int64)


@dataclass(frozen=True, eq=False)
class ParticleRows:
    """The particles one entity holds, ``n`` of them, before they are laid out in the block.

    Attributes:
        position: ``(n, 3)`` [m].
        velocity: ``(n, 3)`` [m/s].
        mass: ``(n,)`` [kg] (or one value for all).
        radius: ``(n,)`` [m] (or one value for all).
        color: ``(n, 3)`` sRGB in [0, 1] (or one colour for all).
        pinned: Indices of its particles that no force moves.
        emitted: True for an emitter's slots: they start dead, and are born.
        data: What the kind's build needs back (a deformable body's spring network).
    """

    position: np.ndarray
    velocity: np.ndarray
    mass: Any
    radius: Any
    color: Any
    pinned: Sequence[int] = ()
    emitted: bool = False
    data: Any = field(default=None, repr=False)

    @property
    def count(self) -> int:
        return int(self.position.shape[0])


class BuildContext:
    """The scene being built and the model's pieces so far (see the module docstring).

    Attributes:
        scene: The validated scene.
        names: Each entity's name (its own, or its type and index: ``emitter2``).
        h: The integrator's step [s], ``dt / substeps``.
        gravity: The world's gravitational acceleration [m/s²], ``(3,)``.
        groups: The particle groups, by entity index (filled by the first pass).
        arrays: The particle block: ``position``, ``velocity``, ``color`` ``(N, 3)``, ``mass``,
            ``radius`` ``(N,)``, ``alive``, ``pinned`` ``(N,)`` bool (filled by the first
            pass; a handle moves its particles to their place at t = 0).
        data: What each particle-holding entity's rows carried for its build, by entity index.
        forces: Forces on particles, in the order they are summed (world gravity first).
        springs: The deformable bodies' springs, in scene order: summed after the other
            forces (the order a step's force sum takes, whatever the scene's order).
        body_forces: Forces on rigid bodies.
        stages: Post-step stages (sorted by phase when the model is made).
        contact_sources: Colliders whose contacts the model reports.
        bodies: The rigid bodies, if the scene has any.
        held: Each handle's motion and the particle indices it holds.
        exempt: Particles that must not meet some colliders (a crowd's agents its walls):
            ``(particles, collider entity indices)``.
        edges, faces: Lines and triangles to draw between particles (particle indices).
        systems: The named systems, whose coordinates follow the particles' in the state.
        emitters: The emitters (their slots are among the particles').
        static: Arrays the recordings keep once, by name (the colliders' scenery).
        attrs: Attributes the recordings keep, by name (the drawn colliders' names).
    """

    def __init__(self, scene: Any, names: Sequence[str], h: float) -> None:
        self.scene = scene
        self.names = list(names)
        self.h = h
        self.gravity = np.asarray(scene.world.gravity, dtype=np.float64)
        self.groups: dict[int, ParticleGroup] = {}
        self.arrays: dict[str, np.ndarray] = {}
        self.data: dict[int, Any] = {}
        self.forces: list[Force] = []
        self.springs: list[Springs] = []
        self.body_forces: list[BodyForce] = []
        self.stages: list[Stage] = []
        self.contact_sources: list[ContactSource] = []
        self.bodies: RigidBodies | None = None
        self.held: list[tuple[HandleMotion, np.ndarray]] = []
        self.exempt: list[tuple[np.ndarray, set[int]]] = []
        self.edges: list[np.ndarray] = []
        self.faces: list[np.ndarray] = []
        self.systems: list[SystemInstance] = []
        self.emitters: list[EmitterSpec] = []
        self.static: dict[str, np.ndarray] = {}
        self.attrs: dict[str, Any] = {}

    @property
    def duration(self) -> float:
        """The scene's duration [s]."""
        return float(self.scene.integration.duration)

    @property
    def particle_count(self) -> int:
        """``N``, the number of particle slots."""
        return int(self.arrays["mass"].shape[0])

    @staticmethod
    def index(where: str) -> int:
        """The entity index of ``where`` (``"entities[3]"`` → 3)."""
        return int(where[where.index("[") + 1 : where.index("]")])

    def group(self, where: str) -> ParticleGroup:
        """The particle slots of the entity at ``where``."""
        return self.groups[self.index(where)]

    def particles_of(self, names: Sequence[str]) -> np.ndarray:
        """The particle indices of the entities called ``names``, in that order."""
        by_name = {g.name: g for g in self.groups.values()}
        chosen = [by_name[name].indices for name in names]
        return np.concatenate(chosen) if chosen else np.zeros(0, np.int64)

    def targets(self, names: Sequence[str] | None) -> Targets:
        """The particles of the entities ``names`` (``None``: every particle)."""
        if names is None:
            return Targets(self.particle_count)
        return Targets(self.particle_count, self.particles_of(names))

    def hold(self, motion: HandleMotion, particles: np.ndarray) -> None:
        """Hold ``particles`` on the path of ``motion`` (they are pinned: no force moves them)."""
        self.held.append((motion, np.asarray(particles, dtype=np.int64)))

    def of_kind(self, kind: str) -> list[tuple[str, Any]]:
        """The ``(where, entity)`` of every entity of type ``kind``, in scene order."""
        return [(f"entities[{i}]", e) for i, e in enumerate(self.scene.entities) if e.type == kind]
