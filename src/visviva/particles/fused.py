"""The fused particle step: one parallel pass per step for scenes made only of particles.

A scene of particles under field forces, with colliders and emitters, stepped by symplectic
Euler (the scenes' default), is bound by memory traffic: the generic pipeline reads and writes
the particle arrays once for each force, for the integrator's kick and drift, for each stage
and for the divergence watch. This module takes the whole step in one pass over the particles,
each one in registers from its load to its store (every core, ``prange``):

1. the acceleration from the fields: uniform gravity, linear drag, wind and damping folded into
   ``g − c_i v + b_i`` (:class:`LinearFields`), and any other field (attractors, vortices,
   quadratic drag, forces on some particles only) by its law (:mod:`visviva.forces.laws`);
2. symplectic Euler: ``v += h a``, ``x += h v`` (:class:`~visviva.integrators.SymplecticEuler`);
3. collisions, by the collision stage's own per-particle function
   (:func:`visviva.collision.response.resolve`);
4. ageing and death, by the emission stage's own per-particle function
   (:func:`visviva.particles.emission.age_one`), and the divergence watch's check;

then the step's births (:meth:`~visviva.particles.emission.Emission.give_birth`). The results
are those of the generic pipeline to round-off (the order of the force sum differs), which
``tests/test_fused.py`` checks. The state's arrays alternate between two buffers, so the step
allocates nothing; a state stays valid until the step after next (copy what you keep:
:class:`~visviva.simulation.Simulation`'s ``state`` already does).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit, prange

from ..collision.response import ParticleCollisions, resolve
from ..forces.fields import Attractor, Damping, Drag, QuadraticDrag, UniformGravity, Vortex
from ..forces.laws import attractor_force, quadratic_drag_force, vortex_air_velocity
from .emission import Emission, age_one

if TYPE_CHECKING:
    from ..forces.base import Force
    from ..ode.state import State

__all__ = ["FusedParticles"]

#: Codes of the fields the kernel evaluates by their law.
_QUADRATIC, _ATTRACTOR, _VORTEX, _DRAG, _DAMPING = 0, 1, 2, 3, 4
#: Most fields evaluated by their law (each particle keeps which apply as bits of a mask).
MAX_LAW_FIELDS = 64


class FusedParticles:
    """The fused step of a particle scene, if it has one (see :meth:`of`)."""

    def __init__(
        self, count: int, forces: tuple[Force, ...], mass: np.ndarray, stages: tuple[Any, ...]
    ) -> None:
        self.count = count
        self.inverse_mass = 1.0 / mass
        self.gravity = np.zeros(3)
        self.drag = 0.0  # Σ k of linear drags on every particle [N·s/m]
        self.air = np.zeros(3)  # Σ k w [N]
        self.damping = 0.0  # Σ γ of damping on every particle [1/s]
        laws = []
        for force in forces:
            every = force.targets.everything
            if isinstance(force, UniformGravity) and every:
                self.gravity += force.gravity
            elif isinstance(force, Drag) and every:
                self.drag += force.coefficient
                self.air += force.coefficient * force.air_velocity
            elif isinstance(force, Damping) and every:
                self.damping += force.rate
            else:
                laws.append(force)
        self.kinds = np.zeros(len(laws), dtype=np.int64)
        self.parameters = np.zeros((len(laws), 12))
        self.law_masks = np.zeros(count, dtype=np.uint64)
        for k, force in enumerate(laws):
            self.kinds[k], row = _law(force)
            self.parameters[k, : len(row)] = row
            self.law_masks[force.targets.indices] |= np.uint64(1) << np.uint64(k)
        self.collisions = next((s for s in stages if isinstance(s, ParticleCollisions)), None)
        self.emission = next((s for s in stages if isinstance(s, Emission)), None)
        self._buffers: list[dict[str, np.ndarray]] = []

    @classmethod
    def of(cls, model: Any, method: str) -> FusedParticles | None:
        """The fused step of ``model`` for ``method``, or ``None`` if it has none: the method
        must be symplectic Euler, the scene made only of particles, every force a field
        (gravitation and penalty contact are not), every stage collisions or emission."""
        if method != "symplectic_euler" or model.systems or not model.particle_count:
            return None
        if not all(isinstance(f, _FIELDS) for f in model.forces):
            return None
        # A stage that declares no compiled form keeps the generic pipeline; of those that
        # do, the fused step knows how to take the collisions' and the emission's place.
        if not all(
            s.compiled and isinstance(s, (ParticleCollisions, Emission)) for s in model.stages
        ):
            return None
        laws = [f for f in model.forces if not (isinstance(f, _FOLDED) and f.targets.everything)]
        if len(laws) > MAX_LAW_FIELDS:
            return None
        return cls(
            model.particle_count, model.forces, np.asarray(model.particle_mass), model.stages
        )

    def step(self, state: State, h: float, t_after: float, limit: float) -> tuple[State, bool]:
        """The state after one step of ``h`` [s] ending at ``t_after``, and whether a particle
        may be beyond the divergence ``limit`` (or not finite): the caller's watch decides."""
        target = self._spare(state)
        q0, v0 = state.parts
        n = 3 * self.count
        x0, u0 = q0[:n].reshape(-1, 3), v0[:n].reshape(-1, 3)
        x1, u1 = target["q"][:n].reshape(-1, 3), target["v"][:n].reshape(-1, 3)
        carried = {name: target[name] for name in state.carried}
        for name, value in state.carried.items():
            if name.startswith("emitter_"):
                carried[name][:] = value
        collisions, emission = self.collisions, self.emission
        laws = self.kinds if self.kinds.shape[0] else None
        bad = _fused(
            x0,
            u0,
            x1,
            u1,
            self.inverse_mass,
            h,
            self.gravity,
            self.drag,
            self.air,
            self.damping,
            laws,
            self.parameters,
            self.law_masks,
            state["particle_alive"],
            carried["particle_alive"],
            state["particle_radius"],
            carried["particle_radius"],
            *_emission_arguments(state, carried, emission),
            *_collision_arguments(collisions),
            limit,
        )
        if emission is not None:
            emission.give_birth(state.t, t_after, x1, u1, carried)
        after = state.from_parts(t_after, (target["q"], target["v"])).with_carried(**carried)
        return after, bad != 0.0

    def _spare(self, state: State) -> dict[str, np.ndarray]:
        """The buffer set the state does not use (two sets, allocated on first use)."""
        if not self._buffers:
            # Copies of the first state, not empty arrays: the kernel relies on a free slot's
            # entries in the target (two steps old) being its parked values.
            for _ in range(2):
                buffer = {"q": np.array(state.parts[0]), "v": np.array(state.parts[1])}
                buffer |= {name: np.array(value) for name, value in state.carried.items()}
                self._buffers.append(buffer)
        first = self._buffers[0]
        return self._buffers[1] if state.parts[0] is first["q"] else first


_FOLDED = (UniformGravity, Drag, Damping)
_FIELDS = (*_FOLDED, QuadraticDrag, Attractor, Vortex)


def _law(force: Force) -> tuple[int, list[float]]:
    """A field's code and parameters for the kernel's law loop."""
    if isinstance(force, QuadraticDrag):
        return _QUADRATIC, [*force.air_velocity, force.coefficient]
    if isinstance(force, Attractor):
        return _ATTRACTOR, [*force.point, force.strength, force.softening**2]
    if isinstance(force, Vortex):
        return _VORTEX, list(force._parameters())
    if isinstance(force, Drag):
        return _DRAG, [*force.air_velocity, force.coefficient]
    if isinstance(force, Damping):
        return _DAMPING, [force.rate]
    raise TypeError(f"{type(force).__name__} has no fused law")  # pragma: no cover


def _emission_arguments(
    state: State, carried: dict[str, np.ndarray], emission: Emission | None
) -> tuple[Any, ...]:
    if emission is None:
        return (None,) * 8
    return (
        state["particle_age"],
        carried["particle_age"],
        state["particle_lifetime"],
        carried["particle_lifetime"],
        state["particle_size"],
        carried["particle_size"],
        emission.slot_emitter,
        emission.size_ramps,
    )


def _collision_arguments(collisions: ParticleCollisions | None) -> tuple[Any, ...]:
    """The collision stage's arrays for the kernel (``collider_masks`` ``None``: none)."""
    if collisions is None:
        return (None, None, None, None, None, 0, None, None, None)
    r = collisions.response
    return (
        collisions.masks,
        r.restitution,
        r.friction,
        r.resting_speed,
        *collisions.kernel_arguments(),
    )


@njit(cache=True, error_model="numpy", inline="always")
def _law_acceleration(k, kinds, table, x, y, z, vx, vy, vz, inverse_mass):  # pragma: no cover
    """The acceleration [m/s²] of one particle from field ``k`` (by its law)."""
    kind = kinds[k]
    p = (
        table[k, 0],
        table[k, 1],
        table[k, 2],
        table[k, 3],
        table[k, 4],
        table[k, 5],
        table[k, 6],
        table[k, 7],
        table[k, 8],
    )  # entries, not a row view (an atomic reference count per particle)
    if kind == _QUADRATIC:
        fx, fy, fz = quadratic_drag_force(vx, vy, vz, p[0], p[1], p[2], p[3])
    elif kind == _ATTRACTOR:
        fx, fy, fz = attractor_force(x, y, z, p[0], p[1], p[2], p[3], p[4], 1.0 / inverse_mass)
    elif kind == _VORTEX:
        ux, uy, uz = vortex_air_velocity(x, y, z, p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7])
        fx, fy, fz = p[8] * (ux - vx), p[8] * (uy - vy), p[8] * (uz - vz)
    elif kind == _DRAG:
        fx, fy, fz = -p[3] * (vx - p[0]), -p[3] * (vy - p[1]), -p[3] * (vz - p[2])
    else:  # damping: −γ m v
        return -p[0] * vx, -p[0] * vy, -p[0] * vz
    return fx * inverse_mass, fy * inverse_mass, fz * inverse_mass


# fmt: off
@njit(cache=True, parallel=True, error_model="numpy")
def _fused(
    x0, v0, x1, v1, inverse_mass, h, g, drag, air, damping, kinds, parameters, law_masks,
    alive0, alive1, radius0, radius1,
    age0, age1, lifetime0, lifetime1, size0, size1, slot_emitter, size_ramps,
    collider_masks, restitution, friction, resting, toi, planes, rows, others, everything,
    limit,
):  # pragma: no cover - compiled
    """The step of the module docstring for every particle; returns a positive or non-finite
    number if a particle may be beyond ``limit`` or not finite (0 otherwise)."""
    # fmt: on
    bad = 0.0
    for i in prange(x0.shape[0]):
        alive = alive0[i]
        if not alive:
            # A free slot stays parked at rest at the origin (the generic pipeline moves it for a
            # step and parks it again: the same zeros), without reading it; if it was free two
            # steps ago too, the target buffer holds exactly that already.
            if not alive1[i]:
                continue
            for k in range(3):
                x1[i, k] = 0.0
                v1[i, k] = 0.0
            alive1[i] = False
            radius1[i] = radius0[i]
            if age0 is not None:
                age1[i], lifetime1[i], size1[i] = age0[i], lifetime0[i], size0[i]
            continue
        x, y, z = x0[i, 0], x0[i, 1], x0[i, 2]
        vx, vy, vz = v0[i, 0], v0[i, 1], v0[i, 2]
        w = inverse_mass[i]
        # The acceleration, then symplectic Euler: kick, drift.
        c = drag * w + damping
        ax = g[0] - c * vx + air[0] * w
        ay = g[1] - c * vy + air[1] * w
        az = g[2] - c * vz + air[2] * w
        if kinds is not None:
            mask = law_masks[i]
            for k in range(kinds.shape[0]):
                if (mask >> np.uint64(k)) & np.uint64(1):
                    bx, by, bz = _law_acceleration(k, kinds, parameters, x, y, z, vx, vy, vz, w)
                    ax += bx
                    ay += by
                    az += bz
        ux, uy, uz = vx + h * ax, vy + h * ay, vz + h * az
        px, py, pz = x + h * ux, y + h * uy, z + h * uz
        radius = radius0[i]
        if collider_masks is not None and alive and collider_masks[i] != 0:
            px, py, pz, ux, uy, uz = resolve(
                x, y, z, vx, vy, vz, px, py, pz, ux, uy, uz, radius, collider_masks[i], h,
                restitution, friction, resting, toi, planes, rows, others, everything,
            )  # fmt: skip
        if age0 is not None:
            lifetime1[i], size1[i] = lifetime0[i], size0[i]
            alive, age1[i], radius = age_one(
                alive, age0[i], lifetime0[i], size0[i], slot_emitter[i], size_ramps, h
            )
            if not alive:
                px = py = pz = ux = uy = uz = 0.0
        alive1[i] = alive
        radius1[i] = radius
        x1[i, 0], x1[i, 1], x1[i, 2] = px, py, pz
        v1[i, 0], v1[i, 1], v1[i, 2] = ux, uy, uz
        # The watch's check, cheaply: a sum that is not finite, or beyond the limit, flags the
        # step (NaN and inf propagate through the sum; a branch per component would cost more
        # than the step); the caller confirms with the exact check.
        size = abs(px) + abs(py) + abs(pz) + abs(ux) + abs(uy) + abs(uz)
        bad += size * 0.0 + (1.0 if size > limit else 0.0)
    return bad
