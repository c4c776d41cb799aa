"""The frozen Model: everything about a scene that does not change while it runs.

Built once from a validated scene (file or :class:`~visviva.model.SceneBuilder`), a Model holds
the entities as structure-of-arrays data with entity-prefixed names (``particle_position``,
``particle_mass``, ...), the named systems with their generalized coordinates, the forces on
particles (world gravity included), the post-step stages (collisions, emission) and the
settings. Its arrays are read-only. :meth:`Model.system` is the view an integrator steps and
:meth:`Model.initial_state` the state a run starts from; what a recording keeps of a state is
:mod:`visviva.simulation.frames`'.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..collision.body_contacts import BodyContacts, BodyContactSet
from ..collision.contact_classes import DEFAULT_GAP, Contacts, ContactSource
from ..collision.particle_contacts import PairContacts, ParticleContacts
from ..entities.context import ParticleGroup
from ..entities.system.block import SystemInstance
from ..errors import ModelError
from ..ode.problems import Problem

if TYPE_CHECKING:
    from ..forces.base import Force
    from ..forces.body_forces import BodyForce
    from ..ode.stage import Stage
    from ..ode.state import State
    from ..ode.system import System
    from ..particles.emitters import EmitterSpec
    from ..rigid.bodies import RigidBodies
    from .scene import Scene

__all__ = ["MAX_STEPS", "Integration", "Model"]

#: Default recording rate when a scene does not set ``record_every`` [frames/s].
DEFAULT_FRAME_RATE = 60.0
#: A fixed-step run may take at most this many integrator steps (substeps included): a billion
#: steps is minutes compiled and hours in NumPy; more is a mistake in dt, not a plan. A scene
#: asking for more is refused when built, a run when it starts.
MAX_STEPS = 10**9
#: Largest default ``record_every``: the most steps a run may take.
MAX_DEFAULT_RECORD_EVERY = MAX_STEPS


def frozen_array(values: Any, dtype: Any = np.float64) -> np.ndarray:
    """A read-only copy of ``values``."""
    array = np.array(values, dtype=dtype)
    array.flags.writeable = False
    return array


@dataclass(frozen=True)
class Integration:
    """How time advances.

    Attributes:
        method: Integrator name.
        dt: Step [s].
        duration: Simulated time [s].
        substeps: Integrator steps per step.
        record_every: Record every k-th step.
        energy_tolerance: Relative energy change beyond which a run of a conservative scene
            ends with a warning, ``max |E(t) − E(0)| / |E(0)|``.
    """

    method: str
    dt: float
    duration: float
    substeps: int
    record_every: int
    energy_tolerance: float = 0.01

    @staticmethod
    def default_record_every(dt: float) -> int:
        """Steps per frame for about :data:`DEFAULT_FRAME_RATE` frames per second (at most
        :data:`MAX_DEFAULT_RECORD_EVERY`, so a tiny dt never asks for more steps than a run
        may take)."""
        return max(1, min(MAX_DEFAULT_RECORD_EVERY, round(1.0 / (DEFAULT_FRAME_RATE * dt))))


@dataclass(frozen=True, eq=False)
class Model:
    """A built scene.

    Attributes:
        name: Scene name.
        scene: The scene description it was built from.
        gravity: Gravitational acceleration [m/s²], shape ``(3,)``.
        integration: Time stepping settings.
        particle_position: Initial positions [m], shape ``(particle_count, 3)``.
        particle_velocity: Initial velocities [m/s], shape ``(particle_count, 3)``.
        particle_mass: Masses [kg], shape ``(particle_count,)``.
        particle_radius: Initial radii [m], shape ``(particle_count,)``.
        particle_color: sRGB colours in [0, 1], shape ``(particle_count, 3)``.
        particle_alive: Which slots hold a particle at the start, ``(particle_count,)``.
        particle_pinned: Which particles are held — where they start, or on their body's
            handle's path (no force moves them), ``(particle_count,)``.
        particle_groups: Which entity each range of particle slots came from.
        systems: The named systems, whose coordinates follow the particles' in the state.
        bodies: The rigid bodies, whose state follows the systems' (``None`` if none).
        body_forces: The forces on the rigid bodies (world gravity first).
        forces: The forces on particles, world gravity first.
        emitters: The emitters (their slots are among the particles').
        contact_sources: The colliders whose contacts :meth:`contacts` reports (the collision
            stage's and the penalty forces').
        stages: The post-step stages, in the order of their phases and orders
            (:class:`~visviva.ode.stage.Phase`; then in the order they were built).
        edges: Lines drawn between particles, ``(E, 2)`` particle indices each (a rope's
            segments).
        faces: Triangles drawn between particles, ``(F, 3)`` particle indices each (a cloth's
            surface).
        recorded_once: Arrays the recordings keep once, by name, from the kinds that draw
            something of their own (the colliders' ``scenery_*``).
        recorded_attrs: Attributes the recordings keep, by name (``scenery_names``).
        output_formats: Extra outputs the scene asks ``visviva run`` for.
        output_fps: Frame rate of videos, viewer and exports [1/s].
        output_speed: Simulated seconds per second of their playback.
        output_trail: Simulated seconds of each point's path drawn behind it [s].
        output_color_by: What colours the points of videos and the viewer: ``"scene"`` or
            ``"speed"``.
        output_camera: The view of videos and the viewer as
            :func:`~visviva.viz.framing.parse_camera` reads it, or ``None``: a framing.
        output_frame: Without a camera, what the view keeps in the picture: ``"all"`` or a
            body's name.
        output_style: How videos and the viewer draw the points: ``"auto"``, ``"day"`` or
            ``"night"``.
        output_follow: A rigid body the camera follows, or ``None``.
        source: The scene file's text, if it came from a file (kept in recordings).
    """

    name: str
    scene: Scene = field(repr=False)
    gravity: np.ndarray
    integration: Integration
    particle_position: np.ndarray
    particle_velocity: np.ndarray
    particle_mass: np.ndarray
    particle_radius: np.ndarray
    particle_color: np.ndarray
    particle_alive: np.ndarray
    particle_pinned: np.ndarray
    particle_groups: tuple[ParticleGroup, ...] = ()
    systems: tuple[SystemInstance, ...] = ()
    bodies: RigidBodies | None = field(default=None, repr=False)
    body_forces: tuple[BodyForce, ...] = field(default=(), repr=False)
    forces: tuple[Force, ...] = field(default=(), repr=False)
    emitters: tuple[EmitterSpec, ...] = field(default=(), repr=False)
    stages: tuple[Stage, ...] = field(default=(), repr=False)
    contact_sources: tuple[ContactSource, ...] = field(default=(), repr=False)
    edges: tuple[np.ndarray, ...] = field(default=(), repr=False)
    faces: tuple[np.ndarray, ...] = field(default=(), repr=False)
    recorded_once: Mapping[str, np.ndarray] = field(default_factory=dict, repr=False)
    recorded_attrs: Mapping[str, Any] = field(default_factory=dict, repr=False)
    output_formats: tuple[str, ...] = ()
    output_fps: float = 30.0
    output_speed: float = 1.0
    output_trail: float = 0.0
    output_color_by: str = "scene"
    output_camera: str | None = None
    output_frame: str = "all"
    output_style: str = "auto"
    output_follow: str | None = None
    source: str | None = field(default=None, repr=False)

    @property
    def particle_count(self) -> int:
        """Number of particle slots (an emitter's count as its capacity)."""
        return self.particle_position.shape[0]

    @property
    def body_count(self) -> int:
        """Number of rigid bodies."""
        return 0 if self.bodies is None else self.bodies.count

    @property
    def coordinate_count(self) -> int:
        """Number of generalized coordinates of the named systems."""
        return sum(s.size for s in self.systems)

    @property
    def conservative(self) -> bool:
        """True if the scene's energy is conserved by the exact dynamics (so a change in it
        measures the integrator's error): no dissipative force, no stage that changes the
        state (collisions, births), no damped system."""
        if any(s.changes_energy for s in self.stages):
            return False
        if not all(f.conservative for f in (*self.forces, *self.body_forces)):
            return False
        return all(s.conservative for s in self.systems)

    @property
    def has_geometry(self) -> bool:
        """True if runs of this model record something to draw: particles, systems' points or
        rigid bodies."""
        return self.particle_count > 0 or self.body_count > 0 or any(s.drawn for s in self.systems)

    def system(self) -> System:
        """A fresh run-time system (with zeroed work counters): the view an integrator steps."""
        from .scene_system import scene_system

        return scene_system(self)

    def problem(self) -> Problem:
        """The scene's smooth dynamics as a plain problem (for ``vv.solve`` and comparisons);
        refused for scenes with collisions or emitters (see
        :func:`~visviva.model.scene_system.as_problem`)."""
        from .scene_system import as_problem

        return as_problem(self)

    def initial_state(self) -> State:
        """The state a run starts from (copies of the model's arrays)."""
        from .scene_system import initial_state

        return initial_state(self)

    def contacts(self, state: State, gap: float = DEFAULT_GAP) -> Contacts:
        """The particle–collider contacts of ``state`` (every collider, impulse and penalty:
        where, how deep, and colliding, resting or separating; see
        :mod:`visviva.collision.contact_classes`)."""
        return Contacts.join([source.contacts(state, gap) for source in self.contact_sources])

    def body_contacts(self, state: State, gap: float = DEFAULT_GAP) -> BodyContactSet:
        """The contacts of ``state``'s rigid bodies with each other and with the colliders:
        pieces within ``gap`` [m] of each other, with points, normals, depths, relative normal
        velocities and classes (see :mod:`visviva.collision.body_contacts`).

        Raises:
            ModelError: If the scene has no ``body_contacts`` entity.
        """
        stage = next((s for s in self.stages if isinstance(s, BodyContacts)), None)
        if stage is None:
            raise ModelError(
                'this scene\'s bodies do not collide: add an entity of type "body_contacts" '
                "(SceneBuilder.add_body_contacts)"
            )
        return stage.contacts(state, gap)

    def pair_contacts(self, state: State, gap: float = DEFAULT_GAP) -> PairContacts:
        """The sphere–sphere contacts of ``state`` among the particles of the scene's
        ``particle_collisions`` (pairs, points, normals, depths, relative normal velocities,
        classes; see :mod:`visviva.collision.particle_contacts`).

        Raises:
            ModelError: If the scene has no ``particle_collisions`` entity.
        """
        stage = next((s for s in self.stages if isinstance(s, ParticleContacts)), None)
        if stage is None:
            raise ModelError(
                "this scene's particles do not collide with each other: add an entity of type "
                '"particle_collisions" (SceneBuilder.add_particle_collisions)'
            )
        return stage.pair_contacts(state, gap)
