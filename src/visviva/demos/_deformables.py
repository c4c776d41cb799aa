"""What the deformable demos measure on their runs: spring forces, loads on pins, strain, energy.

Shared by ``cloth-hang``, ``cloth-drape``, ``flag``, ``hair``, ``jelly``, ``stiffness-study``
and ``refinement-study``. Every quantity is computed from the model's own forces and the
recorded frames, so a demo's check compares the simulation with physics, not with itself.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numba
import numpy as np

from ..deformables.topology import STRETCH
from ..entities.deformable_build import body_networks
from ..forces.springs import Springs
from ..model.builder import SceneBuilder
from ..model.model import Model
from ..simulation.recording import Recording
from ..simulation.simulation import Simulation

#: Standard gravity [m/s²]: the scenes' default world.
GRAVITY = 9.81


@contextmanager
def one_thread() -> Iterator[None]:
    """Numba's parallel kernels on one thread while the block runs.

    The demos' bodies have at most a few hundred points: a parallel kernel then costs more to
    launch and join than it saves (NOTES.md: below a 64 × 64 cloth one thread wins), and on a
    busy two-core machine each join can wait milliseconds for a descheduled thread, while
    projected Newton's conjugate gradients call such kernels thousands of times per simulated
    second. Measured on the 16 × 16 drape, 0.5 s simulated: 1.4 s on one thread, 50 s on two
    with the other core busy. The springs' forces do not depend on the thread count.
    """
    previous = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(previous)


def record_alone(builder: SceneBuilder, duration: float) -> tuple[Model, Simulation, Recording]:
    """The scene's model, its simulation after ``duration`` [s] and the recording of it, run
    on one thread (:func:`one_thread`)."""
    model = builder.build()
    simulation = Simulation(model)
    with one_thread():
        recording = simulation.record(until=duration)
    return model, simulation, recording


def springs_of(model: Model) -> list[Springs]:
    """The scene's spring forces (one per body that has springs)."""
    return [force for force in model.forces if isinstance(force, Springs)]


def spring_pairs(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """Every spring of the scene: its particles ``(S, 2)`` and rest length [m] ``(S,)``."""
    springs = springs_of(model)
    if not springs:
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0)
    return (
        np.concatenate([s.pairs for s in springs]),
        np.concatenate([s.rest_length for s in springs]),
    )


def stretch_pairs(model: Model) -> np.ndarray:
    """The particles ``(S, 2)`` of every body's stretch springs (a cloth's structural springs,
    a soft body's edges): the springs whose strain is the fabric's or the body's stretch."""
    pairs = [np.zeros((0, 2), dtype=np.int64)]
    for network, first in body_networks(model):
        pairs.append(network.pairs[network.family == STRETCH] + first)
    return np.concatenate(pairs)


def spring_forces(model: Model, x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The force [N] of the springs alone (dampers included) on each particle, ``(N, 3)``, at
    positions ``x`` [m] and velocities ``v`` [m/s]."""
    out = np.zeros_like(x)
    for springs in springs_of(model):
        springs.accumulate(0.0, x, v, out)
    return out


def load_on_pins(model: Model, x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The springs' total pull [N] on the pinned particles, ``(3,)``: at rest, minus the pins'
    reaction on the rest of the body, which then balances every other force on it."""
    return spring_forces(model, x, v)[model.particle_pinned].sum(axis=0)


def kinetic_energy(recording: Recording) -> np.ndarray:
    """``½ Σ m v²`` [J] of each recorded frame, ``(frames,)``."""
    mass = recording.static["particle_mass"]
    return 0.5 * np.einsum(
        "i,fij,fij->f", mass, recording["particle_velocity"], recording["particle_velocity"]
    )


def strain(model: Model, points: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """``l/L − 1`` of the springs on ``pairs`` ``(S, 2)`` at ``points`` ``(..., N, 3)`` [m],
    ``L`` their length in the model's initial state (springs are built at rest there)."""
    start = model.particle_position
    rest = np.linalg.norm(start[pairs[:, 1]] - start[pairs[:, 0]], axis=-1)
    length = np.linalg.norm(points[..., pairs[:, 1], :] - points[..., pairs[:, 0], :], axis=-1)
    return length / rest - 1.0


def largest_rise(energy: np.ndarray) -> float:
    """The largest increase [J] of ``energy`` from one recorded frame to the next (negative
    if it only fell)."""
    return float(np.diff(energy).max()) if energy.size > 1 else 0.0
