"""The constant-acceleration Taylor update of seed 002.

``q' = q + v h + ½ a h²``, ``v' = v + a h``: the second-order Taylor polynomial for the position
with the acceleration frozen over the step. It is exact for constant forces (the thrown rock)
but only first order in general, because the velocity update is explicit Euler; and it is not
symplectic — on an undamped oscillator the amplification matrix has determinant
``1 + (ωh)²/2``, so the energy grows by about that factor per step (explicit Euler: ``1 + (ωh)²``).

Reference:
    Seed 002 ("Motion of a point in space": ``x(t + Δt) = x(t) + v(t)Δt + ½a(t)Δt²``);
    R. Parent, *Computer Animation: Algorithms and Techniques*, 3rd ed., 2012, §7.1.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from .base import CompiledStep, Integrator
from .compiled import _memoized, acceleration_adapter, problem_key
from .symplectic import start_acceleration

if TYPE_CHECKING:
    from ..ode.problems import Problem
    from ..ode.state import State
    from ..ode.system import System

__all__ = ["Taylor"]


class Taylor(Integrator):
    """Constant-acceleration Taylor update ``q + v h + ½ a h²`` (seed 002); first order."""

    name = "taylor"
    order = 1
    second_order_only = True
    evaluations_per_step = 1
    cost = "1 f-evaluation"
    reference = "seed 002; Parent 2012, §7.1"
    summary = "Taylor update with frozen acceleration: q + v h + a h^2/2, v + a h"

    def step(self, system: System, state: State, dt: float) -> State:
        a = start_acceleration(system, state)
        q1 = state.q + dt * state.v + (0.5 * dt * dt) * a
        return state.from_parts(state.t + dt, (q1, state.v + dt * a))

    def compiled_step(self, problem: Problem) -> CompiledStep | None:
        key = problem_key(problem)
        if key is None or key[0] != "second_order":
            return None
        accel = acceleration_adapter(problem)
        if accel is None:
            return None
        return _memoized(("taylor", *key), lambda: _kernel(accel, problem.size))


def _kernel(accel: Callable[..., None], n: int) -> CompiledStep:
    import numba

    @numba.njit
    def step(t, h, y, work, fresh):  # pragma: no cover - compiled
        q, v, a = y[:n], y[n:], work[0, :n]
        accel(t, q, v, a)
        for k in range(n):
            q[k] += h * v[k] + 0.5 * h * h * a[k]
            v[k] += h * a[k]
        return 1

    return CompiledStep(step, 1)
