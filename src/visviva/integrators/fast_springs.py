"""Fast mass-spring simulation (Liu et al. 2013): backward Euler for springs by local/global
alternation with one matrix factorized once.

Backward Euler's positions ``x`` minimize ``½ (x − y)ᵀ M (x − y) + h² E(x)`` with the
inertial target ``y = x_n + h v_n + h² M⁻¹ f`` (``f``: every force but the springs' elastic
one, taken at the start of the step) and the springs' energy ``E = Σ ½ k (|x_j − x_i| − L)²``.
Liu et al. write each spring's term with an auxiliary vector ``d`` of length ``L``:

    ½ k (|x_j − x_i| − L)² = min over |d| = L of ½ k |(x_j − x_i) − d|²,

so ``E = min_d ½ xᵀ L x − xᵀ J d`` with ``L = Σ k (e_j − e_i)(e_j − e_i)ᵀ`` (a weighted graph
Laplacian) and ``J d = Σ k (e_j − e_i) dᵀ``. Alternating

* **local**: each ``d = L (x_j − x_i)/|x_j − x_i|``, the closest vector of the right length;
* **global**: ``(M + h² L) x = M y + h² J d``, one linear solve with a matrix that depends on
  neither ``x`` nor ``d`` — factorized once per run and step size (the same ``N × N`` matrix for
  the three coordinates), each solve two triangular sweeps;

never increases the objective (block coordinate descent), so each step is stable whatever the
stiffness, and converges to the backward Euler step. A fixed number of ``iterations`` per step
trades accuracy for speed (the method's point: a few iterations look right); the iterations are
counted as ``newton_iterations``. Pinned particles keep their positions, and those on a moving
handle take its position at the step's end (their rows are taken out of the solve). The
springs' dampers and every other force act explicitly, from the start of the step; colliders
act after it (the collision stage).

References:
    T. Liu, A. W. Bargteil, J. F. O'Brien, L. Kavan, "Fast simulation of mass-spring systems",
    ACM Trans. Graph. 32(6) (2013), 214.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit, prange

from .._validation import whole_number
from .base import Integrator
from .implicit import BackwardEuler

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.system import System

__all__ = ["FastMassSprings"]


class FastMassSprings(Integrator):
    """Liu et al.'s fast mass-spring step (see the module docstring).

    Args:
        iterations: Local/global iterations per step.

    It steps any system that offers its springs as one network (``system.spring_network``:
    ``mass`` and ``pinned`` per point, ``first``/``second``/``rest_length``/``stiffness`` per
    spring, ``elastic(t, x)`` and ``held_positions(t, x)``, as a scene of particles does); any
    other system is stepped by
    :class:`~visviva.integrators.BackwardEuler` instead.
    """

    name = "fast_mass_springs"
    order = 1
    implicit = True
    evaluations_per_step = 1
    cost = "1 force; per iteration: each spring's direction, 3 solves with a prefactored matrix"
    reference = (
        "T. Liu, A. W. Bargteil, J. F. O'Brien, L. Kavan, Fast simulation of mass-spring "
        "systems, ACM TOG 32(6) 2013"
    )
    summary = "Liu et al.'s local/global backward Euler for springs, one factorization per run"

    def __init__(self, *, iterations: int = 10) -> None:
        self.iterations = whole_number("iterations", iterations, minimum=1)
        self._fallback = BackwardEuler()

    def stability_function(self, z: Any) -> np.ndarray:
        """Backward Euler's, which the iteration converges to."""
        return 1.0 / (1.0 - np.asarray(z, dtype=complex))

    def step(self, system: System, state: State, dt: float) -> State:
        network = system.spring_network
        if network is None or state.parts[0].ndim != 1:
            return self._fallback.step(system, state, dt)
        # The factorizations of the run, per step size (a memo: the same for every call).
        solvers: dict[float, _Global] = system.workspace.get(self, dict)
        solver = solvers.get(dt)
        if solver is None:
            solver = solvers[dt] = _Global(network, dt)
        t = state.t
        q, v = state.parts
        count = network.mass.shape[0]
        x_n, v_n = q.reshape(count, 3), v.reshape(count, 3)
        # Everything but the springs' elastic force, from the start of the step.
        other = system.force(t, q, v).reshape(count, 3) - network.elastic(t, x_n)
        target = x_n + dt * v_n + (dt * dt) * other / network.mass[:, None]
        x = x_n + dt * v_n
        held = network.held_positions(t + dt, x_n)  # the pinned where the step ends
        directions = np.empty((network.pairs.shape[0], 3))
        for _ in range(self.iterations):
            _directions(network.first, network.second, network.rest_length, x, directions)
            x = solver.solve(target, directions, held)
            system.counters.newton_iterations += 1
        system.counters.linear_solves += self.iterations
        system.counters.f_evaluations += 1
        v_new = (x - x_n) / dt
        return state.from_parts(t + dt, (x.reshape(q.shape), v_new.reshape(v.shape)))


class _Global:
    """The global step's matrix ``M + h² L`` on the free particles, factorized once, and the
    pieces of its right-hand side."""

    def __init__(self, network: Any, h: float) -> None:
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        count, springs = network.mass.shape[0], network.pairs.shape[0]
        rows = np.concatenate([network.second, network.first])
        signs = np.concatenate([np.ones(springs), -np.ones(springs)])
        k = np.concatenate([network.stiffness, network.stiffness])
        columns = np.concatenate([np.arange(springs), np.arange(springs)])
        # J = Σ k (e_j − e_i) e_sᵀ (N × S); A (N × S) the incidence e_j − e_i.
        incidence = sp.csr_matrix((signs, (rows, columns)), shape=(count, springs))
        self.jacobi = sp.csr_matrix((signs * k, (rows, columns)), shape=(count, springs))
        laplacian = (self.jacobi @ incidence.T).tocsr()
        matrix = (sp.diags(network.mass) + h * h * laplacian).tocsc()
        self.free = np.flatnonzero(~network.pinned)
        self.held = np.flatnonzero(network.pinned)
        self.h2 = h * h
        self.mass = network.mass
        self.coupling = matrix[self.free][:, self.held]
        # The matrix is symmetric positive definite: no pivoting, and an ordering of A + Aᵀ
        # (minimum degree), which on a cloth grid keeps 40 % fewer nonzeros in the factors than
        # SuperLU's default (COLAMD) and solves 1.5× faster (measured at 128²).
        self.factor = splu(
            matrix[self.free][:, self.free].tocsc(),
            permc_spec="MMD_AT_PLUS_A",
            diag_pivot_thresh=0.0,
            options={"SymmetricMode": True},
        )

    def solve(self, target: np.ndarray, directions: np.ndarray, held: np.ndarray) -> np.ndarray:
        """``x`` with ``(M + h² L) x = M y + h² J d`` on the free particles, the pinned ones
        at their rows of ``held``."""
        rhs = self.mass[:, None] * target + self.h2 * (self.jacobi @ directions)
        x = held.copy()
        free = rhs[self.free]
        if self.held.shape[0]:
            free = free - self.coupling @ held[self.held]
        x[self.free] = self.factor.solve(np.asfortranarray(free))
        return x


@njit(cache=True, parallel=True, error_model="numpy")
def _directions(first, second, rest, x, out):  # pragma: no cover - compiled
    """``out[s] = L (x_j − x_i)/|x_j − x_i|`` for spring ``s = (i, j)`` (along x where the ends
    coincide: any direction is as close)."""
    for s in prange(first.shape[0]):
        i, j = first[s], second[s]
        dx, dy, dz = x[j, 0] - x[i, 0], x[j, 1] - x[i, 1], x[j, 2] - x[i, 2]
        length = np.sqrt(dx * dx + dy * dy + dz * dz)
        if length == 0.0:
            out[s, 0], out[s, 1], out[s, 2] = rest[s], 0.0, 0.0
            continue
        scale = rest[s] / length
        out[s, 0], out[s, 1], out[s, 2] = dx * scale, dy * scale, dz * scale
