"""Implicit one-stage methods: backward Euler, the trapezoidal rule and implicit midpoint.

Each step solves one implicit stage with Newton's method (:mod:`.newton`), so the three differ
only in where the stage sits and how the step is assembled from it:

=================  ======  ===========================  =============================
method             θ       stage                        step
=================  ======  ===========================  =============================
backward Euler     1       ``Y = y + h f(t+h, Y)``      ``y' = Y``
trapezoidal        ½       ``Y = y + ½h f(t, y)``       ``y' = Y``
                           ``+ ½h f(t+h, Y)``
implicit midpoint  ½       ``Y = y + ½h f(t+½h, Y)``    ``y' = 2Y − y``
=================  ======  ===========================  =============================

All three are A-stable: stable for every ``h > 0`` on every decaying or oscillating mode.
Backward Euler damps (``|R(iy)| < 1``: it loses energy, seed 000's "overly damped motion") and
is even stable where the exact solution grows (``λ = +1, h > 2``); the trapezoidal rule and
implicit midpoint keep ``|R(iy)| = 1`` exactly, and implicit midpoint is symplectic.

References:
    Seeds 000 and 004; E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd
    ed., Springer 1996, §IV.3; Hairer, Lubich & Wanner 2006, §II.1.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from .base import Integrator
from .newton import NewtonOptions, identity_minus, linear_solve, mass_minus, solve_stage
from .newton_solve import BlockNewtonSolve
from .runge_kutta import ButcherTableau, initial_rate

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.system import System

__all__ = [
    "BackwardEuler",
    "ImplicitMidpoint",
    "ImplicitOneStage",
    "LinearlyImplicitEuler",
    "Trapezoidal",
]


class ImplicitOneStage(Integrator):
    """Common part of the implicit methods: Newton options and assembling the step.

    Args:
        rtol: Newton's relative tolerance on each update component.
        atol: Newton's absolute tolerance on each update component.
        max_iterations: Newton iterations allowed per step before it fails.
    """

    implicit = True
    evaluations_per_step = 1
    cost = "1 Newton solve: per iteration 1 f-evaluation, 1 Jacobian, 1 linear solve"
    tableau: ClassVar[ButcherTableau]
    #: Weight θ of the implicit evaluation and its time as a fraction of the step.
    theta: ClassVar[float]
    stage_time: ClassVar[float]

    def __init__(self, *, rtol: float = 1e-10, atol: float = 1e-12, max_iterations: int = 20):
        self.newton = NewtonOptions(rtol=rtol, atol=atol, max_iterations=max_iterations)

    def stability_function(self, z: Any) -> np.ndarray:
        return self.tableau.stability_function(z)

    def stage_base(self, system: System, state: State, dt: float) -> tuple[np.ndarray, ...]:
        """The explicit part of the stage: the state itself, unless a method adds to it."""
        return state.parts

    def step(self, system: System, state: State, dt: float) -> State:
        theta_h = self.theta * dt
        base = self.stage_base(system, state, dt)
        t_stage = state.t + self.stage_time * dt
        stage, rate = solve_stage(system, t_stage, base, theta_h, self.newton)
        return self.assemble(state, dt, stage, rate)

    def assemble(
        self, state: State, dt: float, stage: tuple[np.ndarray, ...], rate: np.ndarray
    ) -> State:
        """The new state from the solved stage; the end-point rate is cached for the next step."""
        derivative = (stage[1], rate) if len(stage) == 2 else (rate,)
        return state.from_parts(state.t + dt, stage, derivative)


class BackwardEuler(ImplicitOneStage):
    """Backward (implicit) Euler: ``y' = y + h f(t + h, y')`` (seeds 000, 004).

    First order, unconditionally stable on decaying and oscillating modes, and dissipative: an
    undamped oscillator loses energy by the factor ``1/(1 + (ωh)²)`` per step.
    """

    name = "backward_euler"
    order = 1
    theta = 1.0
    stage_time = 1.0
    reference = "seeds 000 and 004; Hairer & Wanner 1996, §IV.3"
    summary = "backward Euler: y' = y + h f(t + h, y'), solved by Newton"
    tableau = ButcherTableau([[1.0]], [1.0], [1.0])


class Trapezoidal(ImplicitOneStage):
    """The trapezoidal rule (Crank–Nicolson): half a step of explicit, half of implicit Euler.

    Second order; ``|R(iy)| = 1``, so an undamped linear oscillator keeps its energy exactly,
    but stiff decaying modes are barely damped (``R(−∞) = −1``).
    """

    name = "trapezoidal"
    order = 2
    theta = 0.5
    stage_time = 1.0
    reference = "seed 000; J. Crank, P. Nicolson, Proc. Camb. Phil. Soc. 43 (1947) 50"
    summary = "trapezoidal rule: y' = y + h/2 (f(t, y) + f(t + h, y'))"
    tableau = ButcherTableau([[0.0, 0.0], [0.5, 0.5]], [0.5, 0.5], [0.0, 1.0])

    def stage_base(self, system: System, state: State, dt: float) -> tuple[np.ndarray, ...]:
        rate = initial_rate(system, state)
        return tuple(part + (0.5 * dt) * r for part, r in zip(state.parts, rate, strict=True))


class ImplicitMidpoint(ImplicitOneStage):
    """Implicit midpoint: ``y' = y + h f(t + ½h, ½(y + y'))``, the one-stage Gauss method.

    Second order, symplectic and time-reversible: it conserves every quadratic invariant
    (angular momentum, the energy of linear systems) exactly up to the Newton tolerance.
    """

    name = "implicit_midpoint"
    order = 2
    symplectic = True
    theta = 0.5
    stage_time = 0.5
    reference = "Hairer, Lubich & Wanner 2006, §II.1 and §VI.4"
    summary = "implicit midpoint: slope at the mean of the old and new state"
    tableau = ButcherTableau([[0.5]], [1.0], [0.5])

    def assemble(
        self, state: State, dt: float, stage: tuple[np.ndarray, ...], rate: np.ndarray
    ) -> State:
        # y' = 2Y − y; the rate is at the midpoint, not at y', so nothing is cached.
        return state.from_parts(
            state.t + dt, tuple(2.0 * s - p for s, p in zip(stage, state.parts, strict=True))
        )


class LinearlyImplicitEuler(BlockNewtonSolve, Integrator):
    """Backward Euler with one Newton iteration: Baraff & Witkin's implicit cloth step.

    The force is linearized at the start of the step, ``F(q + Δq, v + Δv) ≈ F + K Δq + D Δv``
    (``K = ∂F/∂q``, ``D = ∂F/∂v``), and with ``Δq = h (v + Δv)`` backward Euler becomes one
    linear system,

        (M − h D − h² K) Δv = h (F + h K v),    v' = v + Δv,    q' = q + h v',

    (first-order problems: ``(I − h J) Δy = h f(t, y)``, the Rosenbrock–Euler method). It is
    exact backward Euler on linear problems — same stability function ``1/(1 − z)``, stable for
    every step on decaying and oscillating modes — and on nonlinear ones it never "fails to
    converge": there is nothing to converge, one solve per step. The price is accuracy where
    the force is far from linear over a step (first order still). ``K`` is the forces'
    definite Jacobian where the system has one (springs without a compressed spring's negative
    stiffness), which keeps the matrix positive definite when a cloth buckles.

    On a scene's particles (3×3 block-sparse Jacobians) the system is solved as
    :class:`~.projected_newton.ProjectedNewton` solves each of its Newton iterations (see
    :mod:`.newton_solve`): by CG with a multigrid preconditioner unless asked otherwise, to a
    tighter ``cg_rtol`` by default (1e-3, not 1e-2), since no later iteration corrects what CG
    leaves: on ``benchmarks/bench_implicit_cloth.py``'s 64² cloth after 21 steps of 1/60 s, the
    lowest point is 0.2 mm from where CG at 1e-4 puts it and 8 mm from converged backward
    Euler's (the linearization's error). Other systems take a direct solve.

    Args:
        linear_solver: ``"cg"`` or ``"direct"`` (a sparse LU factorization).
        preconditioner: CG's: ``"multigrid"`` or ``"jacobi"``.
        cg_rtol: Relative residual CG reaches.
        cg_max_iterations: CG iterations allowed per step.
    """

    name = "linearly_implicit_euler"
    order = 1
    implicit = True
    evaluations_per_step = 1
    cost = "1 f-evaluation, 1 Jacobian and 1 linear solve"
    reference = "D. Baraff, A. Witkin, Large steps in cloth simulation, SIGGRAPH 1998, §3"
    summary = "backward Euler linearized once per step (Baraff & Witkin): no Newton iterations"

    def __init__(
        self,
        *,
        linear_solver: str = "cg",
        preconditioner: str = "multigrid",
        cg_rtol: float = 1e-3,
        cg_max_iterations: int = 1000,
    ) -> None:
        self._configure_solve(linear_solver, preconditioner, cg_rtol, cg_max_iterations)

    def stability_function(self, z: Any) -> np.ndarray:
        return 1.0 / (1.0 - np.asarray(z, dtype=complex))

    def step(self, system: System, state: State, dt: float) -> State:
        t = state.t
        system.counters.newton_iterations += 1  # the one iteration
        if not system.second_order:
            (y,) = state.parts
            rate = system.rhs(t, y)
            matrix = identity_minus(system.jacobian(t, y, rate), dt, y.shape)
            return state.from_parts(t + dt, (y + linear_solve(system, matrix, dt * rate),))
        q, v = state.parts
        force = system.force(t, q, v)
        # Definite: a buckling spring's negative stiffness would make the matrix indefinite
        # and the linearized step blow up (Baraff & Witkin; Choi & Ko 2002).
        stiffness, damping = system.force_jacobian(t, q, v, force, form="definite")
        rhs = dt * (force + dt * _product(stiffness, v))
        mass = system.mass
        if mass is None or mass.kind == "diagonal":
            diagonal = np.ones_like(v) if mass is None else mass.diagonal()
            change, _ = self._solve(
                system, np.broadcast_to(diagonal, v.shape), stiffness, damping, dt, rhs
            )
        else:
            matrix = mass_minus(mass, damping, stiffness, dt, v.shape)
            change = linear_solve(system, matrix, rhs)
        v_new = v + change
        return state.from_parts(t + dt, (q + dt * v_new, v_new))


def _product(matrix: Any, vector: np.ndarray) -> np.ndarray:
    """``matrix @ vector`` for a sparse, dense or batched dense ``(batch, n, n)`` matrix."""
    if vector.ndim == 2 and np.ndim(matrix) == 3:
        return np.einsum("bij,bj->bi", matrix, vector)
    return np.asarray(matrix @ vector).reshape(vector.shape)
