"""Symplectic methods on the split state ``(q, v)``: symplectic Euler, velocity Verlet, leapfrog.

Each alternates *kicks* (``v += h·a``, :func:`kick`) and *drifts* (``q += h·v``, :func:`drift`;
for a rigid body's orientation, a rotation by its angular momentum: ``Kinematics.drift``).
The two are written once, here: the methods below, their compiled kernels and the fused
particle step (:mod:`visviva.particles.fused`) all call them. For forces
that depend on position only, every one of these maps is symplectic: it conserves a
*modified* energy ``H̃ = H + O(h^p)`` exactly, so the true energy oscillates within
``O(h^p)`` of its initial value for exponentially long times instead of drifting (seed 001).
Velocity Verlet and leapfrog are also time-reversible: running backwards with ``−v`` retraces
the trajectory to round-off.

With velocity-dependent forces (damping, drag) no explicit method is symplectic, and a plain
kick that reads a stale velocity drops Verlet and leapfrog to first order. Here they evaluate
the force with an Euler-predicted velocity instead, which keeps second order at the cost of one
more evaluation per step (for velocity Verlet this is Groot & Warren's λ = 1 scheme).

References:
    E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed., Springer 2006,
    §I.1 and §VI.3; L. Verlet, Phys. Rev. 159 (1967) 98; W. C. Swope et al., J. Chem. Phys. 76
    (1982) 637; R. D. Groot, P. B. Warren, J. Chem. Phys. 107 (1997) 4423.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from .base import CompiledStep, Integrator
from .compiled import _memoized, acceleration_adapter, problem_key

if TYPE_CHECKING:
    from ..ode.problems import Problem
    from ..ode.state import State
    from ..ode.system import SecondOrderSystem, System

__all__ = [
    "Leapfrog",
    "SymplecticEuler",
    "SymplecticEulerPositionFirst",
    "VelocityVerlet",
    "drift",
    "kick",
]


@njit(cache=True, inline="always")
def kick(v, a, h):  # pragma: no cover - compiled
    """The velocity after a kick of ``h`` [s] at the acceleration ``a``: ``v + h a``
    (numbers or arrays)."""
    return v + h * a


@njit(cache=True, inline="always")
def drift(q, v, h):  # pragma: no cover - compiled
    """The position after a drift of ``h`` [s] at the velocity ``v``: ``q + h v``."""
    return q + h * v


def start_acceleration(system: SecondOrderSystem, state: State):
    """``q''`` at the state, reusing what the previous step left in the state."""
    if state.acceleration is not None:
        return state.acceleration
    return system.acceleration(state.t, state.q, state.v)


def _drift(system: SecondOrderSystem, q: np.ndarray, v: np.ndarray, h: float) -> np.ndarray:
    """``q + h v``, or the system's kinematics' drift (rigid bodies' rotations)."""
    kinematics = system.kinematics
    return drift(q, v, h) if kinematics is None else kinematics.drift(q, v, h)


def _derivative(system: SecondOrderSystem, q: np.ndarray, v: np.ndarray, a: np.ndarray):
    """The derivative ``(q', v')`` of a state whose acceleration ``a`` is known."""
    kinematics = system.kinematics
    return (v if kinematics is None else kinematics.rate(q, v)), a


class _Split(Integrator):
    """A method that needs the split ``(q, v)`` state; its drifts go through
    ``system.drift``, so it steps orientations too (rigid bodies)."""

    second_order_only = True
    symplectic = True
    manifold_positions = True

    def _compile(self, problem: Problem, make: Callable[..., CompiledStep]) -> CompiledStep | None:
        key = problem_key(problem)
        if key is None or key[0] != "second_order":
            return None
        accel = acceleration_adapter(problem)
        if accel is None:
            return None
        n = problem.size
        velocity_dependent = problem.velocity_dependent
        return _memoized((self.name, *key), lambda: make(accel, n, velocity_dependent))


class SymplecticEuler(_Split):
    """Symplectic Euler, velocity first (the "semi-implicit Euler" of game engines).

    ``v' = v + h a(t, q, v)``, then ``q' = q + h v'``: first order, one evaluation per step, and
    stable for undamped oscillations up to ``ωh = 2``, where explicit Euler is never stable.
    """

    name = "symplectic_euler"
    order = 1
    evaluations_per_step = 1
    cost = "1 f-evaluation"
    reference = "Hairer, Lubich & Wanner 2006, Thm VI.3.3; seed 001"
    summary = "symplectic Euler, kick then drift: v += h a(q); q += h v"

    def step(self, system: System, state: State, dt: float) -> State:
        a = start_acceleration(system, state)
        v1 = kick(state.v, a, dt)
        return state.from_parts(state.t + dt, (_drift(system, state.q, v1, dt), v1))

    def compiled_step(self, problem: Problem) -> CompiledStep | None:
        return self._compile(problem, _symplectic_euler_kernel)


class SymplecticEulerPositionFirst(_Split):
    """Symplectic Euler, position first: ``q' = q + h v``, then ``v' = v + h a(t + h, q', v)``.

    The adjoint of :class:`SymplecticEuler`; same order, stability and energy behaviour.
    """

    name = "symplectic_euler_position_first"
    order = 1
    evaluations_per_step = 1
    cost = "1 f-evaluation"
    reference = "Hairer, Lubich & Wanner 2006, Thm VI.3.3"
    summary = "symplectic Euler, drift then kick: q += h v; v += h a(q')"

    def step(self, system: System, state: State, dt: float) -> State:
        t1 = state.t + dt
        q1 = _drift(system, state.q, state.v, dt)
        a = system.acceleration(t1, q1, state.v)
        v1 = kick(state.v, a, dt)
        # For position-only forces `a` is exactly the acceleration of the new state.
        if system.velocity_dependent:
            return state.from_parts(t1, (q1, v1))
        return state.from_parts(t1, (q1, v1), _derivative(system, q1, v1, a))

    def compiled_step(self, problem: Problem) -> CompiledStep | None:
        return self._compile(problem, _symplectic_euler_position_first_kernel)


class VelocityVerlet(_Split):
    """Velocity Verlet (kick–drift–kick leapfrog), the workhorse of molecular dynamics.

    ``v½ = v + ½h a``, ``q' = q + h v½``, ``v' = v½ + ½h a(q')``. Second order, symplectic and
    time-reversible; one evaluation per step because the end acceleration starts the next step.
    Energy error stays below about ``(ωh)²/4`` of the energy for an oscillator of frequency ``ω``.
    """

    name = "velocity_verlet"
    order = 2
    evaluations_per_step = 1
    cost = "1 f-evaluation (2 with velocity-dependent forces)"
    reference = "Swope, Andersen, Berens & Wilson 1982; Verlet 1967"
    summary = "velocity Verlet: half kick, drift, half kick"

    def step(self, system: System, state: State, dt: float) -> State:
        a0 = start_acceleration(system, state)
        t1 = state.t + dt
        v_half = kick(state.v, a0, 0.5 * dt)
        q1 = _drift(system, state.q, v_half, dt)
        if system.velocity_dependent:
            a1 = system.acceleration(t1, q1, kick(state.v, a0, dt))
            return state.from_parts(t1, (q1, kick(v_half, a1, 0.5 * dt)))
        a1 = system.acceleration(t1, q1, v_half)
        v1 = kick(v_half, a1, 0.5 * dt)
        return state.from_parts(t1, (q1, v1), _derivative(system, q1, v1, a1))

    def compiled_step(self, problem: Problem) -> CompiledStep | None:
        return self._compile(problem, _velocity_verlet_kernel)


class Leapfrog(_Split):
    """Leapfrog in drift–kick–drift form (position Verlet, Störmer's method).

    ``q½ = q + ½h v``, ``v' = v + h a(t + ½h, q½)``, ``q' = q½ + ½h v'``. Second order,
    symplectic and time-reversible, one evaluation per step (two with velocity-dependent forces).
    """

    name = "leapfrog"
    order = 2
    evaluations_per_step = 1
    cost = "1 f-evaluation (2 with velocity-dependent forces)"
    reference = "C. Störmer 1907; Hairer, Lubich & Wanner 2006, §I.3"
    summary = "leapfrog / position Verlet: half drift, kick, half drift"

    def step(self, system: System, state: State, dt: float) -> State:
        t_half = state.t + 0.5 * dt
        q_half = _drift(system, state.q, state.v, 0.5 * dt)
        v_mid = state.v
        if system.velocity_dependent:
            a0 = start_acceleration(system, state)
            v_mid = kick(state.v, a0, 0.5 * dt)
        a = system.acceleration(t_half, q_half, v_mid)
        v1 = kick(state.v, a, dt)
        return state.from_parts(state.t + dt, (_drift(system, q_half, v1, 0.5 * dt), v1))

    def compiled_step(self, problem: Problem) -> CompiledStep | None:
        return self._compile(problem, _leapfrog_kernel)


# Compiled one-system kernels. `y` is the stacked state [q, v]; row 0 of `work` holds the
# acceleration between calls, row 1 a predicted velocity. Each returns its evaluation count.


def _symplectic_euler_kernel(accel: Callable[..., None], n: int, vd: bool) -> CompiledStep:
    import numba

    @numba.njit
    def step(t, h, y, work, fresh):  # pragma: no cover - compiled
        q, v, a = y[:n], y[n:], work[0, :n]
        accel(t, q, v, a)
        for k in range(n):
            v[k] = kick(v[k], a[k], h)
            q[k] = drift(q[k], v[k], h)
        return 1

    return CompiledStep(step, 1)


def _symplectic_euler_position_first_kernel(
    accel: Callable[..., None], n: int, vd: bool
) -> CompiledStep:
    import numba

    @numba.njit
    def step(t, h, y, work, fresh):  # pragma: no cover - compiled
        q, v, a = y[:n], y[n:], work[0, :n]
        for k in range(n):
            q[k] = drift(q[k], v[k], h)
        accel(t + h, q, v, a)
        for k in range(n):
            v[k] = kick(v[k], a[k], h)
        return 1

    return CompiledStep(step, 1)


def _velocity_verlet_kernel(accel: Callable[..., None], n: int, vd: bool) -> CompiledStep:
    import numba

    @numba.njit
    def step(t, h, y, work, fresh):  # pragma: no cover - compiled
        q, v, a, predicted = y[:n], y[n:], work[0, :n], work[1, :n]
        evaluations = 1
        if fresh or vd:
            accel(t, q, v, a)
            evaluations = 2
        for k in range(n):
            predicted[k] = kick(v[k], a[k], h)
            v[k] = kick(v[k], a[k], 0.5 * h)
            q[k] = drift(q[k], v[k], h)
        if vd:
            accel(t + h, q, predicted, a)
        else:
            accel(t + h, q, v, a)
        for k in range(n):
            v[k] = kick(v[k], a[k], 0.5 * h)
        return evaluations

    return CompiledStep(step, 2)


def _leapfrog_kernel(accel: Callable[..., None], n: int, vd: bool) -> CompiledStep:
    import numba

    @numba.njit
    def step(t, h, y, work, fresh):  # pragma: no cover - compiled
        q, v, a, mid = y[:n], y[n:], work[0, :n], work[1, :n]
        evaluations = 1
        if vd:
            accel(t, q, v, a)
            evaluations = 2
            for k in range(n):
                mid[k] = kick(v[k], a[k], 0.5 * h)
        else:
            for k in range(n):
                mid[k] = v[k]
        for k in range(n):
            q[k] = drift(q[k], v[k], 0.5 * h)
        accel(t + 0.5 * h, q, mid, a)
        for k in range(n):
            v[k] = kick(v[k], a[k], h)
            q[k] = drift(q[k], v[k], 0.5 * h)
        return evaluations

    return CompiledStep(step, 2)
