"""The view of a scene that an integrator steps: one second-order system over every entity.

The integrated arrays are ``q`` and ``v``: the ``N`` particles' positions (and velocities)
flattened, then the ``m`` generalized coordinates of the named systems, in scene order, then
the ``B`` rigid bodies' ``(x, q)`` and ``(P, L)`` (:mod:`visviva.rigid.motion`; ``q`` has
``3N + m + 7B`` entries, ``v`` ``3N + m + 6B``). Named parts are views into them
(:class:`~visviva.ode.state.Layout`), with ``n = 3N + m``:

    particle_position      (N, 3) [m]          q[0 : 3N]
    particle_velocity      (N, 3) [m/s]        v[0 : 3N]
    generalized_position   (m,)                q[3N : n]
    generalized_velocity   (m,)                v[3N : n]
    body_position          (B, 3) [m]          q[n : n + 3B]       centres of mass
    body_orientation       (B, 4)              q[n + 3B : n + 7B]  unit quaternions (w, x, y, z)
    body_momentum          (B, 3) [kg m/s]     v[n : n + 3B]
    body_angular_momentum  (B, 3) [kg m²/s]    v[n + 3B : n + 6B]  world frame

so a particle scene's integrator works on its particle arrays without a copy. The force is the
particle forces' sum (:class:`~visviva.forces.ForceSum`) beside each system's own equations;
the mass matrix is diagonal (each particle's mass on its three coordinates, and 1 for the
systems, which give accelerations); the Jacobian, when every piece has an analytic one, is the
block-diagonal of the particle forces' sparse Jacobian and the systems' dense ones. A scene
made of a first-order system alone (Dahlquist's test equation) is that system, part ``y``.
The bodies' rows of the force are their forces and torques (``P' = F``, ``L' = τ``, unit mass),
their positions move by the system's kinematics (:class:`~visviva.rigid.motion.BodyMotion`),
and implicit methods do not step them.

Pinned particles feel no force (their rows of the force and of its Jacobians are zero). Those on
a handle (:mod:`visviva.particles.handles`) are moreover put where their handle holds them at
the time of each evaluation — positions and velocities — before the forces are summed, so every
integrator's springs pull from the handle's true place at every stage of a step.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ModelError
from ..forces.assembly import ForceSum
from ..forces.springs import Springs
from ..ode.mass import Mass
from ..ode.problems import Problem, SecondOrderProblem
from ..ode.state import Layout, PartView, State
from ..ode.system import ContactConstraints, FirstOrderSystem, SecondOrderSystem
from ..ode.workspace import Workspace
from ..particles.handles import Handles

if TYPE_CHECKING:
    from ..ode.system import System
    from .model import Model

__all__ = ["SceneSystem", "SpringView", "as_problem", "initial_state", "layout", "scene_system"]


def _first_order(model: Model) -> bool:
    return len(model.systems) == 1 and model.systems[0].problem.kind == "first_order"


def layout(model: Model) -> Layout:
    """The names of a scene's parts (see the module docstring)."""
    if _first_order(model):
        return Layout.first_order()
    n, end = 3 * model.particle_count, 3 * model.particle_count + model.coordinate_count
    shape = (model.particle_count, 3)
    views = []
    if model.particle_count:
        views += [
            PartView("particle_position", 0, 0, n, shape, "m"),
            PartView("particle_velocity", 1, 0, n, shape, "m/s"),
        ]
    if model.systems:
        views += [
            PartView("generalized_position", 0, n, end),
            PartView("generalized_velocity", 1, n, end),
        ]
    if model.bodies is not None:
        b = model.bodies.count
        views += [
            PartView("body_position", 0, end, end + 3 * b, (b, 3), "m"),
            PartView("body_orientation", 0, end + 3 * b, end + 7 * b, (b, 4)),
            PartView("body_momentum", 1, end, end + 3 * b, (b, 3), "kg m/s"),
            PartView("body_angular_momentum", 1, end + 3 * b, end + 6 * b, (b, 3), "kg m^2/s"),
        ]
    return Layout(True, tuple(views))


def initial_state(model: Model) -> State:
    """The state a run of ``model`` starts from."""
    if _first_order(model):
        problem = model.systems[0].problem
        return State(problem.t0, (problem.y0.copy(),), layout(model))
    bodies = model.bodies
    q = np.concatenate(
        [model.particle_position.ravel()]
        + [s.problem.q0 for s in model.systems]  # type: ignore[attr-defined]
        + ([] if bodies is None else [bodies.positions()])
    )
    v = np.concatenate(
        [model.particle_velocity.ravel()]
        + [s.problem.v0 for s in model.systems]  # type: ignore[attr-defined]
        + ([] if bodies is None else [bodies.momenta()])
    )
    carried: dict[str, np.ndarray] = {}
    if model.particle_count:
        carried["particle_alive"] = model.particle_alive.copy()
        carried["particle_radius"] = model.particle_radius.copy()
    for stage in model.stages:  # parts a stage keeps (ages, warm starts, exit times)
        carried |= stage.carried_start()
    return State(0.0, (q, v), layout(model), MappingProxyType(carried))


def scene_system(model: Model) -> System:
    """The system an integrator steps for ``model`` (see the module docstring)."""
    names = layout(model)
    if _first_order(model):
        only = model.systems[0].problem.system()
        return FirstOrderSystem(
            only.rhs,
            jacobian=only.jacobian if only.has_jacobian else None,
            energy=(lambda t, y: only.energy(State(t, (y,)))) if only.has_energy else None,
            layout=names,
        )
    count = model.particle_count
    n = 3 * count
    work = Workspace()  # the run's: each system is made for one run
    forces = ForceSum(model.forces, count, work)
    pieces = [(s.offset + n, s.offset + n + s.size, s.problem.system()) for s in model.systems]
    end = n + model.coordinate_count  # where the bodies start in q and v
    bodies = model.bodies
    b = model.body_count
    mass = Mass(
        np.concatenate(
            [np.repeat(model.particle_mass, 3), np.ones(model.coordinate_count + 6 * b)]
        ),
        np.zeros(end + 6 * b),
    )
    motion = None if bodies is None else bodies.motion(end)

    # Pinned particles feel no net force, so they keep their place (and zero velocity) under
    # every integrator, explicit or implicit: their rows and columns of the Jacobians are
    # zero too, which takes them out of Newton's linear systems. Those on a handle are put on
    # its path first (`placed`): nothing then depends on their integrated values, so the zero
    # columns are exact.
    held = np.flatnonzero(np.repeat(model.particle_pinned, 3))
    held_blocks = None
    if held.shape[0] and forces.has_jacobian:
        pinned = model.particle_pinned
        block_rows = np.repeat(np.arange(count), np.diff(forces.indptr))
        held_blocks = np.flatnonzero(pinned[block_rows] | pinned[forces.indices])
    handles = next((s for s in model.stages if isinstance(s, Handles)), None)

    def placed(t: float, q: np.ndarray, v: np.ndarray | None) -> tuple[Any, Any]:
        """The particles' positions and velocities ``(count, 3)`` from ``q`` and ``v``, those
        on handles where their handles hold them at ``t``."""
        x = q[:n].reshape(count, 3)
        u = None if v is None else v[:n].reshape(count, 3)
        return (x, u) if handles is None else handles.hold(t, x, u)

    def force(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        out = np.zeros_like(v)
        if count:
            forces.accumulate(t, *placed(t, q, v), out[:n].reshape(count, 3))
            out[held] = 0.0
        for first, last, piece in pieces:
            out[first:last] = piece.acceleration(t, q[first:last], v[first:last])
        if b:
            x, orientation, momentum, spin = _body_parts(q, v, end, b)
            wrench = out[end:].reshape(2, b, 3)  # forces, then torques (views)
            for body_force in model.body_forces:
                body_force.accumulate_wrench(t, x, orientation, momentum, spin, *wrench)
        return out

    def jacobian(t: float, q: np.ndarray, v: np.ndarray, form: str = "exact") -> tuple[Any, Any]:
        import scipy.sparse as sp

        stiffness, damping = [], []
        if count:
            x, u = placed(t, q, v)
            dfdx, dfdv = forces.jacobian(t, x, u, form)
            if dfdv is None and velocity_dependent:
                dfdv = sp.bsr_matrix(
                    (np.zeros_like(dfdx.data), forces.indices, forces.indptr), shape=dfdx.shape
                )
            for matrix in (dfdx, dfdv):
                if held_blocks is not None and matrix is not None:
                    matrix.data[held_blocks] = 0.0
            if not pieces:
                return dfdx, dfdv  # block-sparse, 3×3 blocks, as the forces' sum gives it
            stiffness.append(dfdx)
            damping.append(dfdv if dfdv is not None else sp.csr_matrix((n, n)))
        for first, last, piece in pieces:
            dq, dv = piece.force_jacobian(t, q[first:last], v[first:last])
            size = last - first
            stiffness.append(sp.csr_matrix(dq))
            damping.append(sp.csr_matrix((size, size)) if dv is None else sp.csr_matrix(dv))
        return sp.block_diag(stiffness, format="csr"), (
            sp.block_diag(damping, format="csr") if velocity_dependent else None
        )

    def energy(t: float, q: np.ndarray, v: np.ndarray, carried: Any) -> float:
        total = 0.0
        if count:
            alive = carried["particle_alive"]
            x, u = q[:n].reshape(count, 3), v[:n].reshape(count, 3)
            total += 0.5 * float(np.einsum("i,ij,ij->", model.particle_mass * alive, u, u))
            total += forces.potential(t, x, alive)
        for first, last, piece in pieces:
            value = piece.energy(State(t, (q[first:last], v[first:last])))
            total += 0.0 if value is None else float(value)
        if motion is not None:
            total += motion.kinetic_energy(q, v)
            x, orientation, _, _ = _body_parts(q, v, end, b)
            total += sum(f.potential(t, x, orientation) for f in model.body_forces)
        return total

    def potential(t: float, q: np.ndarray) -> float:
        return forces.potential(t, placed(t, q, None)[0])

    velocity_dependent = (
        forces.velocity_dependent
        or any(p.velocity_dependent for *_, p in pieces)
        or any(f.velocity_dependent for f in model.body_forces)
    )
    analytic = forces.has_jacobian and all(p.has_jacobian for *_, p in pieces) and not b
    system = SceneSystem(
        force,
        mass=mass,
        velocity_dependent=velocity_dependent,
        jacobian=jacobian if analytic else None,
        energy=energy,
        layout=names,
        workspace=work,
        kinematics=motion,
    )
    particles_only = count and not pieces and not b
    if particles_only and forces.gradient_form and not _damped_handles(model, handles):
        system.potential = potential
    system.contact_constraints = _contact_constraints(model)
    springs = [f for f in model.forces if isinstance(f, Springs)]
    if springs and not pieces and not b:
        network = SpringView(
            model.particle_mass, model.particle_pinned, tuple(springs), handles, work
        )
        system.spring_network = network
    return system


def _body_parts(
    q: np.ndarray, v: np.ndarray, start: int, count: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Views of the bodies' ``x`` ``(B, 3)``, ``q`` ``(B, 4)``, ``P`` and ``L`` ``(B, 3)`` in
    the integrated arrays, the bodies starting at entry ``start``."""
    x = q[start : start + 3 * count].reshape(count, 3)
    orientation = q[start + 3 * count : start + 7 * count].reshape(count, 4)
    momentum = v[start : start + 3 * count].reshape(count, 3)
    spin = v[start + 3 * count : start + 6 * count].reshape(count, 3)
    return x, orientation, momentum, spin


@dataclass(frozen=True)
class SpringView:
    """A scene's springs as one network, for solvers made for springs
    (:mod:`visviva.deformables.fast_springs`).

    Attributes:
        mass: ``(N,)`` particle masses [kg].
        pinned: ``(N,)`` which particles are held (in place, or by a handle).
        forces: The scene's :class:`~visviva.forces.Springs`.
        handles: The scene's handles, if it has any.
        work: The run's storage (the springs' scratch).
    """

    mass: np.ndarray
    pinned: np.ndarray
    forces: tuple[Springs, ...]
    handles: Handles | None = None
    work: Workspace | None = None

    def held_positions(self, t: float, x: np.ndarray) -> np.ndarray:
        """The positions ``x`` ``(N, 3)`` [m] with the particles on handles where their handles
        hold them at ``t`` [s]: ``x`` itself if the scene has no handles, else a copy."""
        return x if self.handles is None else self.handles.hold(t, x)[0]

    @cached_property
    def pairs(self) -> np.ndarray:
        """``(S, 2)`` every spring's particles."""
        return np.concatenate([f.pairs for f in self.forces])

    @cached_property
    def first(self) -> np.ndarray:
        return np.ascontiguousarray(self.pairs[:, 0])

    @cached_property
    def second(self) -> np.ndarray:
        return np.ascontiguousarray(self.pairs[:, 1])

    @cached_property
    def rest_length(self) -> np.ndarray:
        """``(S,)`` [m]."""
        return np.concatenate([f.rest_length for f in self.forces])

    @cached_property
    def stiffness(self) -> np.ndarray:
        """``(S,)`` [N/m]."""
        return np.concatenate([f.stiffness for f in self.forces])

    def elastic(self, t: float, x: np.ndarray) -> np.ndarray:
        """``(N, 3)`` the springs' elastic forces [N] at positions ``x`` (no damper)."""
        out = np.zeros_like(x)
        still = np.zeros_like(x)
        for force in self.forces:
            force.accumulate(t, x, still, out, self.work)
        return out


def _damped_handles(model: Model, handles: Handles | None) -> bool:
    """True if a damped spring ends on a handled particle. Its damper then pulls the other end
    by the handle's velocity, a force that depends on positions but is no gradient: the scene's
    force is no longer ``−∇U + D v``, and implicit steps must not minimize an incremental
    potential."""
    if handles is None:
        return False
    on_handle = np.zeros(model.particle_count, dtype=bool)
    on_handle[handles.indices] = True
    return any(
        bool((on_handle[f.pairs].any(axis=1) & (f.damping > 0.0)).any())
        for f in model.forces
        if isinstance(f, Springs)
    )


def _contact_constraints(model: Model) -> ContactConstraints | None:
    """``(q, reach) ↦ (particles, normals, push, friction)``: the particles inside the impulse
    colliders at positions ``q`` or within ``reach`` [m] of them (one contact per particle, the
    deepest), their colliders' outward normals, how far [m] each must move along its normal to
    sit just outside (half the touching gap: the collision stage then finds nothing to undo,
    and the next step still finds it touching) and the colliders' friction coefficients μ;
    ``None`` for a scene without impulse colliders or with emitters (whose live particles
    change between steps)."""
    from ..collision.contact_classes import DEFAULT_GAP, Contacts, find_contacts
    from ..collision.response import ParticleCollisions

    stages = [s for s in model.stages if isinstance(s, ParticleCollisions)]
    if not stages or model.emitters:
        return None
    count = model.particle_count
    radius = model.particle_radius
    alive = np.ones(count, dtype=bool)
    friction = np.concatenate([s.response.friction for s in stages])

    def constraints(q: np.ndarray, reach: float) -> tuple[np.ndarray, ...]:
        x = q[: 3 * count].reshape(count, 3)
        still = np.zeros_like(x)
        found = Contacts.join(
            [
                find_contacts(
                    x,
                    still,
                    radius,
                    alive,
                    s.masks,
                    s.colliders,
                    s.response.resting_speed,
                    s.labels,
                    max(reach, DEFAULT_GAP),
                )
                for s in stages
            ]
        )
        order = np.argsort(found.depth, kind="stable")  # the deepest last: it wins
        push = found.depth[order] + 0.5 * DEFAULT_GAP
        return found.particle[order], found.normal[order], push, friction[found.collider[order]]

    return constraints


class SceneSystem(SecondOrderSystem):
    """A scene's second-order system; its energy counts only live particles (it reads the
    state's carried ``particle_alive``), and it gives the forces' symmetric or definite
    Jacobian (springs without their damper's non-symmetric part, and without a compressed
    spring's negative stiffness) to implicit steps that ask."""

    #: Its particles' Jacobians are block-sparse with 3×3 blocks (BSR), on a fixed pattern.
    block_jacobian = True

    def force_jacobian(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        force: np.ndarray | None = None,
        *,
        form: str = "exact",
    ) -> tuple[Any, Any]:
        if form == "exact" or self._jacobian is None:
            return super().force_jacobian(t, q, v, force, form=form)
        self.counters.jacobian_evaluations += 1
        return self._jacobian(t, q, v, form)  # type: ignore[call-arg]

    def energy(self, state: State) -> np.ndarray | None:
        """Kinetic plus potential energy [J] of ``state``: live particles and systems."""
        q, v = state.parts
        return np.asarray(self._energy(state.t, q, v, state.carried), dtype=np.float64)  # type: ignore[misc]


def as_problem(model: Model) -> Problem:
    """The scene's smooth dynamics as a plain problem, for ``vv.solve``, comparisons of
    methods and convergence studies: the one system of a scene that holds nothing else, or
    every entity as one second-order problem over the coordinates of :func:`layout`.

    Raises:
        ModelError: For a scene with stages (collisions, emitters), which a plain problem cannot
            express, or rigid bodies, whose orientations do not move as ``q' = v``.
    """
    if model.bodies is not None:
        raise ModelError(
            "this scene has rigid bodies, whose orientations do not move as q' = v (a plain "
            "problem's): run it with vv.Simulation or visviva run"
        )
    if model.stages:
        raise ModelError(
            "this scene has collisions, emitters or moving handles, which change its state "
            "between steps: run it with vv.Simulation or visviva run (a plain problem has only "
            "smooth dynamics)"
        )
    if len(model.systems) == 1 and not model.particle_count:
        return model.systems[0].problem
    system = scene_system(model)
    start = initial_state(model)
    q0, v0 = start.parts

    def energy(t: float, q: np.ndarray, v: np.ndarray) -> Any:
        return system._energy(t, q, v, start.carried)

    def moving(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return system._force(t, q, v)

    def still(t: float, q: np.ndarray) -> np.ndarray:
        return system._force(t, q, v0)  # a force that ignores the velocities

    force = moving if system.velocity_dependent else still
    mass = system.mass.values  # type: ignore[union-attr]  # a scene system always has one
    return SecondOrderProblem.from_force(force, mass, q0, v0, energy=energy, name=model.name)
