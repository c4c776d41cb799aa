"""Backward Euler as an energy minimization: projected Newton with a line search and CG.

For forces of the form ``F(q, v) = −∇U(q) + D(q) v`` (springs, gravity, linear damping,
conservative penalty contact), the backward Euler step ``M (V − v) = h F(q + hV, V)`` is the
stationary point of the *incremental potential*

    Φ(V) = ½ (V − v)ᵀ M (V − v) + U(q + hV) − ½ h Vᵀ D V                    [J]

with the dampers' ``D`` held at the first iterate (so the dampers act along their directions
at the start of the step; ``∇Φ`` is then the residual ``g(V) = M (V − v) − h F``), and its
minimum where ``Φ`` is convex. Newton's method on ``g`` gets what makes optimization robust
(Gast et al. 2015; Martin et al. 2011):

* **projection**: the Newton matrix ``A = M − h D − h² K`` with each force's stiffness made
  positive semi-definite (a compressed spring's negative stiffness dropped, see
  :meth:`~visviva.forces.Springs.add_jacobian`; Teran et al. 2005) is symmetric
  positive definite, so every Newton direction ``d = −A⁻¹ g`` goes downhill (``gᵀd < 0``).
  That is the default (``"always"``). The projected matrix may converge only linearly where
  springs are compressed, so ``"adaptive"`` first tries the exact Hessian and falls back to the
  projected one where CG meets negative curvature or the last step had to be shortened (Longva
  et al. 2023). Measured on a 64² cloth falling from horizontal (h = 1/60 s, 30 steps), the
  projected matrix took as many Newton iterations (7.5 a step) and 20–25 % less time; and with
  the multigrid preconditioner CG seldom meets the negative curvature of a buckled cloth, so
  the exact Hessian's Newton steps can end on a saddle of ``Φ``, where the energy may grow;
* **a backtracking line search** on ``Φ`` (Armijo: ``Φ(V + αd) ≤ Φ(V) + c α gᵀd``, halving
  ``α``): a step into a buckled, energy-raising configuration is shortened instead of taken;
* **preconditioned conjugate gradients** (:mod:`.block_cg`, with an aggregation multigrid
  cycle as the preconditioner, :mod:`.multigrid`) solve ``A d = −g`` inexactly (to
  ``cg_rtol``; Newton corrects the rest) — or a direct sparse factorization, for comparison;
* the iteration starts from the previous step's acceleration, ``V₀ = v + h a``, and stops when
  Newton's decrement, as a mass-weighted RMS velocity ``√(−gᵀd/Σm)``, is below ``atol +
  rtol·(RMS speed)`` (:func:`_decrement_ratio`);
* a step that does not converge within ``max_iterations`` is retried as two half steps, up to
  :data:`SPLITS` times, before :class:`~visviva.errors.NewtonConvergenceError` is raised;
* the colliders' contacts, where the system offers them, are held inside the solve, with
  Coulomb friction (:mod:`.contact_set`, :mod:`.friction`).

A system whose force is not of that form (wind, damped penalty contact, generalized
coordinates) has no potential; the line search then asks for a smaller residual ``‖g‖``.
:class:`ProjectedTrapezoidal` solves the trapezoidal rule's implicit half the same way.

References:
    T. F. Gast, C. Schroeder, A. Stomakhin, C. Jiang, J. M. Teran, "Optimization integrator for
    large time steps", IEEE TVCG 21 (2015) 1103–1115.
    S. Martin, B. Thomaszewski, E. Grinspun, M. Gross, "Example-based elastic materials",
    SIGGRAPH 2011 (backward Euler as minimization of an incremental potential).
    J. Teran, E. Sifakis, G. Irving, R. Fedkiw, "Robust quasistatic finite elements and flesh
    simulation", SCA 2005 (projecting each element's stiffness to be definite).
    A. Longva, F. Löschner, J. A. Fernández-Fernández, E. Larionov, U. M. Ascher, J. Bender,
    "Pitfalls of projection: a study of Newton-type solvers for incremental potentials",
    arXiv:2311.14526 (2023) (projecting on demand).
    J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006, §3.1 (Armijo
    backtracking) and §7.1 (inexact Newton–CG).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit

from ..errors import ModelError, NewtonConvergenceError
from .bsr import block_product
from .contact_set import hold_contacts
from .friction import LaggedFriction
from .implicit import BackwardEuler, Trapezoidal
from .newton import NewtonOptions, stop_if_asked
from .newton_solve import BlockNewtonSolve, same_blocks

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.system import SecondOrderSystem, System

__all__ = ["ProjectedNewton", "ProjectedTrapezoidal"]

#: When the Newton matrix uses the forces' definite (projected) stiffness.
PROJECTIONS = ("adaptive", "always", "never")
#: Times a step whose Newton iteration does not converge may be halved (down to h/8).
SPLITS = 3
#: Armijo's fraction of the predicted decrease a step must achieve.
ARMIJO = 1e-4
#: Halvings the line search may take (the shortest step is 2⁻¹² of Newton's).
HALVINGS = 12
#: Relative round-off allowed in comparing incremental potentials (sums of large terms).
ROUNDOFF = 1e-13


class ProjectedNewton(BlockNewtonSolve, BackwardEuler):
    """Backward Euler solved as an energy minimization (see the module docstring).

    Args:
        rtol: Tolerance on Newton's correction relative to the velocities (both as
            mass-weighted RMS, see :func:`_decrement_ratio`).
        atol: Absolute tolerance on Newton's correction [m/s].
        max_iterations: Newton iterations allowed per step.
        projection: When the Newton matrix uses each force's stiffness made definite:
            ``"always"``, ``"never"`` (the exact Jacobian), or ``"adaptive"`` (projected until
            a full step is accepted, then exact while full steps are accepted and CG finds
            the matrix positive definite; best with ``preconditioner="jacobi"``, whose many
            iterations find negative curvature).
        line_search: Shorten steps that do not decrease the incremental potential enough.
        linear_solver: ``"cg"`` (preconditioned conjugate gradients) or ``"direct"``.
        preconditioner: CG's: ``"multigrid"`` (an aggregation multigrid cycle, whose iterations
            grow slowly with the resolution; :mod:`.multigrid`) or ``"jacobi"`` (the inverted
            3×3 diagonal blocks).
        cg_rtol: Relative residual CG reaches in each Newton iteration.
        cg_max_iterations: CG iterations allowed per linear solve.

    Systems it is not made for (plain problems, batches, scenes whose forces lack analytic
    Jacobians) are stepped by :class:`BackwardEuler`'s plain Newton iteration (the trapezoidal
    rule's, for :class:`ProjectedTrapezoidal`) with its default tolerances.
    """

    name = "projected_newton"
    order = 1
    cost = (
        "per Newton iteration: 1 force, 1 Jacobian, 1 CG solve (1 matrix product per CG "
        "iteration), 1 energy per line-search trial"
    )
    reference = (
        "Gast et al., Optimization integrator for large time steps, TVCG 2015; "
        "Baraff & Witkin 1998; Nocedal & Wright 2006, §3.1, §7.1"
    )
    summary = "backward Euler as energy minimization: projected Newton, line search, CG"

    def __init__(
        self,
        *,
        rtol: float = 1e-3,
        atol: float = 1e-4,
        max_iterations: int = 30,
        projection: str = "always",
        line_search: bool = True,
        linear_solver: str = "cg",
        cg_rtol: float = 1e-2,
        cg_max_iterations: int = 1000,
        preconditioner: str = "multigrid",
    ) -> None:
        super().__init__()  # the plain Newton iteration's own tolerances, where it steps
        self.tolerance = NewtonOptions(rtol=rtol, atol=atol, max_iterations=max_iterations)
        if projection not in PROJECTIONS:
            raise ModelError(
                f"`projection` must be one of {', '.join(map(repr, PROJECTIONS))} "
                f"(got {projection!r})"
            )
        self._configure_solve(linear_solver, preconditioner, cg_rtol, cg_max_iterations)
        self.projection = projection
        self.line_search = bool(line_search)

    def step(self, system: System, state: State, dt: float) -> State:
        if not _takes(system, state):
            return super().step(system, state, dt)
        q, v = state.parts
        acceleration = state.acceleration
        q, v, acceleration = self._advance(system, state.t, q, v, acceleration, dt, SPLITS)  # type: ignore[arg-type]
        return state.from_parts(state.t + dt, (q, v), (v, acceleration))

    def _advance(
        self,
        system: SecondOrderSystem,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        acceleration: np.ndarray | None,
        h: float,
        splits: int,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(q, v, a)`` after one step of ``h`` [s] — or, if Newton does not converge in it,
        after two of ``h/2``, each split again up to ``splits`` times (the failed attempts
        count as ``rejected_steps``). The implicit stage is ``M (V − v_b) = θh F(q_b + θhV,
        V)`` with ``(q_b, v_b) = (q, v) + (1 − θ) h (v, a)``: backward Euler for ``θ = 1``,
        the trapezoidal rule for ``θ = ½``."""
        guess = v if acceleration is None else v + h * acceleration
        theta_h = self.theta * h
        q_base, v_base = q, v
        if self.theta < 1.0:
            start = acceleration if acceleration is not None else system.acceleration(t, q, v)
            q_base = q + (h - theta_h) * v
            v_base = v + (h - theta_h) * start
        constraints = system.contact_constraints
        try:
            if constraints is None:
                v_new, _ = self._minimize(system, t + h, q_base, v_base, guess, theta_h, None)
            else:

                def minimize(
                    v: np.ndarray, normals: np.ndarray, friction: Any, rough: float
                ) -> tuple[np.ndarray, np.ndarray]:
                    return self._minimize(
                        system, t + h, q_base, v_base, v, theta_h, normals, friction, rough
                    )

                v_new = hold_contacts(minimize, constraints, q_base, guess, theta_h)
        except NewtonConvergenceError:
            if splits == 0:
                raise
            system.counters.rejected_steps += 1
            half = 0.5 * h
            q, v, acceleration = self._advance(system, t, q, v, acceleration, half, splits - 1)
            return self._advance(system, t + half, q, v, acceleration, half, splits - 1)
        return q_base + theta_h * v_new, v_new, (v_new - v_base) / theta_h

    def _minimize(
        self,
        system: SecondOrderSystem,
        t: float,
        q_base: np.ndarray,
        v_base: np.ndarray,
        v: np.ndarray,
        h: float,
        normals: np.ndarray | None,
        friction: LaggedFriction | None = None,
        rough: float = 1.0,
    ) -> tuple[np.ndarray, np.ndarray]:
        """``V`` with ``M (V − v_b) = h F(t, q_b + hV, V)``, from the guess ``v``, and the
        residual at the last iterate; with ``normals`` ``(N, 3)`` (unit rows for held
        particles, zero rows for free ones), only across the held particles' normals, and
        with ``friction``'s impulses on them; ``rough``: stop at that many times the
        tolerance."""
        mass = np.ones_like(v) if system.mass is None else system.mass.diagonal()
        mass = np.broadcast_to(mass, v.shape)
        potential = system.potential
        counters = system.counters
        newton = self.tolerance
        iteration, norm = 0, np.inf
        adaptive = self.projection == "adaptive"
        exact = self.projection != "always"
        held = None  # the dampers' matrix D, held from the first iterate when there is Φ
        rest = np.zeros_like(v)
        while iteration < newton.max_iterations:
            stop_if_asked(t)
            iteration += 1
            counters.newton_iterations += 1
            q = q_base + h * v
            for form in ("symmetric", "definite") if exact else ("definite",):
                stiffness, damping = system.force_jacobian(t, q, v, form=form)
                if potential is not None:
                    held = damping if held is None else held
                    damping = held
                    force = system.force(t, q, rest) + _product(held, v)
                else:
                    force = system.force(t, q, v)
                residual = mass * (v - v_base) - h * force
                extra = None
                if friction is not None:
                    residual = residual + friction.gradient(v).reshape(v.shape)
                    extra = friction.blocks(v)
                free = residual if normals is None else _across(normals, residual)
                direction, positive = self._solve(
                    system, mass, stiffness, damping, h, -free, normals, extra
                )
                if positive or not adaptive:
                    break
            norm = _decrement_ratio(free, direction, mass, v, newton.atol, newton.rtol)
            if not np.isfinite(norm):
                break
            if norm <= rough:
                return v + direction, residual
            step = 1.0
            if self.line_search:
                merit = _Merit(system, t, q_base, v_base, mass, h, damping, potential, friction)
                step = merit.backtrack(v, direction, free)
            v = v + step * direction
            if adaptive:
                exact = step == 1.0
        raise NewtonConvergenceError(
            f"projected Newton did not converge in the backward Euler step ending at t={t!r} "
            f"after {iteration} iterations ("
            + (
                "the iterates became non-finite"
                if not np.isfinite(norm)
                else f"the last Newton direction was {norm:.3g} times the tolerance"
            )
            + "). Reduce dt, raise max_iterations, or loosen rtol/atol.",
            t=t,
            step=None,
            iterations=iteration,
            update_norm=norm,
        )


class ProjectedTrapezoidal(ProjectedNewton):
    """The trapezoidal rule solved like :class:`ProjectedNewton`: half a step of explicit
    Euler, then the implicit half ``M (V − v_b) = ½h F(q_b + ½hV, V)`` as the minimum of its
    incremental potential, with the same projection, line search, CG, contacts and friction.

    Second order and without the numerical damping of backward Euler (``|R(iy)| = 1``): an
    undamped cloth keeps its energy instead of losing it step by step, which makes it the
    choice for lively, springy motion — at the price of stiff modes that are not damped
    either (``R(−∞) = −1``: they ring).
    """

    name = "projected_trapezoidal"
    order = 2
    theta = 0.5
    tableau = Trapezoidal.tableau
    stage_base = Trapezoidal.stage_base
    reference = (
        "seed 000; Gast et al., Optimization integrator for large time steps, TVCG 2015; "
        "Crank & Nicolson 1947"
    )
    summary = "trapezoidal rule as energy minimization: projected Newton, line search, CG"


def _takes(system: System, state: State) -> bool:
    """Whether the minimization road suits the system (see :class:`ProjectedNewton`): a
    scene's, whose Jacobians are 3×3 block-sparse, one at a time, with a diagonal mass."""
    if not system.block_jacobian or state.parts[0].ndim != 1:
        return False
    mass = system.mass  # type: ignore[union-attr]
    return (mass is None or mass.kind == "diagonal") and system.has_jacobian


def _across(normals: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """``vector`` (flat, ``3N``) without its components along each row of ``normals``."""
    rows = vector.reshape(-1, 3)
    along = np.einsum("ij,ij->i", rows, normals)
    return (rows - along[:, None] * normals).reshape(vector.shape)


def _product(matrix: Any, v: np.ndarray) -> np.ndarray:
    """``matrix @ v`` for a 3×3 block-sparse ``matrix`` (``0`` for ``None``)."""
    if matrix is None:
        return np.zeros_like(v)
    if not same_blocks(matrix, None):
        return np.asarray(matrix @ v)
    out = np.empty((v.size // 3, 3))
    block_product(matrix.indptr, matrix.indices, matrix.data, v.reshape(-1, 3), out)
    return out.reshape(v.shape)


class _Merit:
    """What the line search decreases: the incremental potential where the system has one,
    else half the residual's squared norm (see the module docstring)."""

    def __init__(
        self,
        system: SecondOrderSystem,
        t: float,
        q_base: np.ndarray,
        v_base: np.ndarray,
        mass: np.ndarray,
        h: float,
        damping: Any,
        potential: Any,
        friction: LaggedFriction | None = None,
    ) -> None:
        self.system, self.t, self.q_base, self.v_base = system, t, q_base, v_base
        self.mass, self.h, self.damping, self.potential = mass, h, damping, potential
        self.friction = friction

    def value(self, v: np.ndarray) -> tuple[float, float]:
        """The merit at ``V`` and the size of its terms (to judge round-off by)."""
        change = v - self.v_base
        q = self.q_base + self.h * v
        if self.potential is None:
            residual = self.mass * change - self.h * self.system.force(self.t, q, v)
            value = 0.5 * _inner(residual, residual)
            return value, value
        inertia = 0.5 * _inner(self.mass * change, change)
        energy = float(self.potential(self.t, q))
        dissipation = -0.5 * self.h * _inner(v, _product(self.damping, v))
        if self.friction is not None:
            dissipation += self.friction.potential(v)
        return inertia + energy + dissipation, abs(inertia) + abs(energy) + abs(dissipation)

    def backtrack(self, v: np.ndarray, direction: np.ndarray, residual: np.ndarray) -> float:
        """The step ``α`` along ``direction`` from ``V`` that Armijo's rule accepts (the last
        halving's if none does: Newton's stopping rule judges what follows)."""
        start, scale = self.value(v)
        # The merit's slope along the direction: gᵀd for Φ (∇Φ = g); for ½‖g‖² along Newton's
        # direction, −‖g‖².
        slope = -2.0 * start if self.potential is None else _inner(residual, direction)
        step = 1.0
        for _ in range(HALVINGS):
            trial, size = self.value(v + step * direction)
            if trial <= start + ARMIJO * step * slope + ROUNDOFF * max(scale, size):
                return step
            step *= 0.5
            self.system.counters.line_search_steps += 1
        return step


def _decrement_ratio(
    residual: np.ndarray,
    direction: np.ndarray,
    mass: np.ndarray,
    v: np.ndarray,
    atol: float,
    rtol: float,
) -> float:
    """Newton's remaining correction measured against ``atol + rtol·|V|``, both as mass-weighted
    RMS velocities [m/s]: the correction's is ``√(−gᵀd / Σm)``, Newton's decrement in velocity
    units. Since ``A ⪰ M``, ``dᵀMd ≤ dᵀAd = −gᵀd``: it bounds the RMS velocity error of the
    step; and soft directions (a cloth's bending), in which a small residual allows a large but
    harmless correction, do not hold the iteration back as a per-component test would."""
    with np.errstate(invalid="ignore", over="ignore"):
        total = float(mass.sum())
        correction = np.sqrt(abs(_inner(residual, direction)) / total)
        speed = np.sqrt(_inner(mass * v, v) / total)
        ratio = correction / (atol + rtol * speed)
    return ratio if np.isfinite(ratio) and np.isfinite(direction).all() else float("inf")


@njit(cache=True)
def _inner(a, b):  # pragma: no cover - compiled
    """``a · b`` for flat vectors, on this thread. Not ``np.dot``: OpenBLAS runs it on its own
    threads, whose waiting spins take the cores from Numba's (measured: 16 ms instead of 3 µs
    for 12,288 numbers with the two cores busy)."""
    total = 0.0
    for i in range(a.shape[0]):
        total += a[i] * b[i]
    return total
