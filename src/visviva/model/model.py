"""The frozen Model: everything about a scene that does not change while it runs.

Built once from a validated scene (file or :class:`~visviva.model.SceneBuilder`), a Model holds
structure-of-arrays particle data with entity-prefixed names, the world, the integration
settings and at most one named system. Its arrays are read-only. :meth:`Model.problem` turns it
into the ordinary second- or first-order problem that the one simulation loop runs, and
:meth:`Model.frame_fields` turns recorded states back into geometry (``points`` [m]) for the
video, viewer and exporters.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..forces import UniformGravity
from ..ode.problems import Problem, SecondOrderProblem
from .systems import SYSTEMS

__all__ = ["Integration", "Model", "ParticleGroup", "SystemInstance"]

#: Default recording rate when a scene does not set ``record_every`` [frames/s].
DEFAULT_FRAME_RATE = 60.0
#: Largest default ``record_every``: the most steps a run may take (simulation.loop.MAX_STEPS).
MAX_DEFAULT_RECORD_EVERY = 10**9


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


@dataclass(frozen=True)
class ParticleGroup:
    """A named range of particles that came from one scene entity.

    Attributes:
        name: Entity name.
        start: First particle index.
        count: Number of particles.
    """

    name: str
    start: int
    count: int


@dataclass(frozen=True)
class SystemInstance:
    """A named system with its parameter values (defaults filled in)."""

    name: str
    system: str
    parameters: Mapping[str, float]


@dataclass(frozen=True, eq=False)
class Model:
    """A built scene.

    Attributes:
        name: Scene name.
        gravity: Gravitational acceleration [m/s²], shape ``(3,)``.
        integration: Time stepping settings.
        particle_position: Initial positions [m], shape ``(particle_count, 3)``.
        particle_velocity: Initial velocities [m/s], shape ``(particle_count, 3)``.
        particle_mass: Masses [kg], shape ``(particle_count,)``.
        particle_radius: Radii [m], shape ``(particle_count,)``.
        particle_groups: Which entity each range of particles came from.
        system: The named system, if the scene holds one instead of particles.
        output_formats: Extra outputs the scene asks ``visviva run`` for.
        output_fps: Frame rate of videos, viewer and exports [1/s].
        output_speed: Simulated seconds per second of their playback.
        output_trail: Simulated seconds of each point's path drawn behind it [s].
        source: The scene file's text, stored in recordings for reproducibility.
    """

    name: str
    gravity: np.ndarray
    integration: Integration
    particle_position: np.ndarray
    particle_velocity: np.ndarray
    particle_mass: np.ndarray
    particle_radius: np.ndarray
    particle_groups: tuple[ParticleGroup, ...] = ()
    system: SystemInstance | None = None
    output_formats: tuple[str, ...] = ()
    output_fps: float = 30.0
    output_speed: float = 1.0
    output_trail: float = 0.0
    source: str | None = field(default=None, repr=False)

    @property
    def particle_count(self) -> int:
        """Number of particles."""
        return self.particle_position.shape[0]

    @property
    def conservative(self) -> bool:
        """True if the scene's energy is conserved by the exact dynamics (so a change in it
        measures the integrator's error): particles under gravity, undamped systems."""
        if self.system is None:
            return True
        return SYSTEMS[self.system.system].conservative(self.system.parameters)

    @property
    def has_geometry(self) -> bool:
        """True if runs of this model record drawable ``points``."""
        if self.system is None:
            return True
        kind = SYSTEMS[self.system.system]
        return kind.state_is_points or kind.draw is not None

    def problem(self) -> Problem:
        """The problem the simulation loop runs: particles as one second-order system with
        ``q`` = positions flattened to ``(3N,)``, or the named system's own problem."""
        if self.system is not None:
            return SYSTEMS[self.system.system].build(self.system.parameters, self.gravity)
        count = self.particle_count
        gravity = UniformGravity(self.gravity, self.particle_mass)
        mass3 = np.repeat(self.particle_mass, 3)

        def force(t: float, q: np.ndarray) -> np.ndarray:
            out = np.zeros(q.shape[:-1] + (count, 3))
            x = q.reshape(out.shape)
            gravity.accumulate(t, x, x, out)
            return out.reshape(q.shape)

        def energy(t: float, q: np.ndarray, v: np.ndarray) -> Any:
            kinetic = 0.5 * np.sum(mass3 * v**2, axis=-1)
            return kinetic + gravity.potential(t, q.reshape(q.shape[:-1] + (count, 3)))

        return SecondOrderProblem.from_force(
            force,
            mass3,
            self.particle_position.reshape(-1),
            self.particle_velocity.reshape(-1),
            energy=energy,
            name=self.name,
        )

    def frame_fields(self, parts: tuple[np.ndarray, ...]) -> dict[str, np.ndarray]:
        """Recorded fields for frames of states: ``parts`` are ``(frames, …)`` arrays.

        Particles, and systems whose coordinates are positions (n bodies), give ``points`` [m]
        and ``velocities`` [m/s], ``(frames, N, 3)``; another named system gives its
        coordinates and, if it has a picture, ``points``. Each quantity is recorded once.
        """
        system = self.system
        if system is None or SYSTEMS[system.system].state_is_points:
            q, v = parts
            shape = (q.shape[0], q.shape[-1] // 3, 3)
            return {"points": q.reshape(shape), "velocities": v.reshape(shape)}
        draw = SYSTEMS[system.system].draw
        names = ("y",) if len(parts) == 1 else ("q", "v")
        fields = dict(zip(names, parts, strict=True))
        if draw is not None:
            fields["points"] = draw(system.parameters, self.gravity, parts)
        return fields

    def static(self) -> dict[str, np.ndarray]:
        """Arrays recorded once: particle radii and masses, or a system's edges."""
        if self.system is None:
            return {"radius": np.array(self.particle_radius), "mass": np.array(self.particle_mass)}
        edges = SYSTEMS[self.system.system].edges
        return {} if edges is None else {"edges": np.array(edges, dtype=np.int64)}

    def units(self) -> dict[str, str]:
        """Units of the recorded fields and static arrays."""
        energy = "J" if self.system is None else SYSTEMS[self.system.system].energy_unit
        return {"points": "m", "velocities": "m/s", "radius": "m", "mass": "kg", "energy": energy}
