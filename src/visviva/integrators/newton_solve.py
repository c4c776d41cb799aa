"""The linear solve of an implicit step on a scene's particles: ``(M − h D − h² K) d = r``.

Backward Euler's Newton iterations (:class:`~.projected_newton.ProjectedNewton`) and Baraff &
Witkin's linearized step (:class:`~.implicit.LinearlyImplicitEuler`) both solve a system whose
matrix is the mass minus ``h`` times the damping Jacobian minus ``h²`` times the stiffness
Jacobian, 3×3 block-sparse on the springs' pattern. :class:`BlockNewtonSolve` gives them the
same solver: the matrix's blocks assembled by one kernel, then block CG (:mod:`.block_cg`)
preconditioned by an aggregation multigrid cycle (:mod:`.multigrid`) or by its inverted
diagonal blocks, or a direct sparse factorization for comparison.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit, prange

from .._validation import real_number, whole_number
from ..errors import ModelError
from .block_cg import block_cg
from .multigrid import Hierarchy
from .newton import linear_solve, mass_minus

if TYPE_CHECKING:
    from ..ode.system import System

__all__ = ["LINEAR_SOLVERS", "PRECONDITIONERS", "BlockNewtonSolve", "newton_blocks", "same_blocks"]

#: How the Newton matrix is solved.
LINEAR_SOLVERS = ("cg", "direct")
#: CG's preconditioners.
PRECONDITIONERS = ("multigrid", "jacobi")


class BlockNewtonSolve:
    """The Newton matrix's solver, for integrators to inherit (see the module docstring).

    Attributes set by :meth:`_configure_solve`: ``linear_solver`` (``"cg"`` or ``"direct"``),
    ``preconditioner`` (``"multigrid"`` or ``"jacobi"``), ``cg_rtol`` (the relative residual CG
    reaches), ``cg_max_iterations``.
    """

    def _configure_solve(
        self, linear_solver: str, preconditioner: str, cg_rtol: float, cg_max_iterations: int
    ) -> None:
        if linear_solver not in LINEAR_SOLVERS:
            raise ModelError(f"`linear_solver` must be 'cg' or 'direct' (got {linear_solver!r})")
        if preconditioner not in PRECONDITIONERS:
            raise ModelError(
                f"`preconditioner` must be one of {', '.join(map(repr, PRECONDITIONERS))} "
                f"(got {preconditioner!r})"
            )
        self.linear_solver = linear_solver
        self.preconditioner = preconditioner
        self.cg_rtol = real_number("cg_rtol", cg_rtol, positive=True)
        self.cg_max_iterations = whole_number("cg_max_iterations", cg_max_iterations, minimum=1)

    def _solve(
        self,
        system: System,
        mass: np.ndarray,
        stiffness: Any,
        damping: Any,
        h: float,
        rhs: np.ndarray,
        normals: np.ndarray | None = None,
        extra: np.ndarray | None = None,
    ) -> tuple[np.ndarray, bool]:
        """The Newton direction ``d`` with ``(M − h D − h² K + E) d = rhs``, ``E`` the
        block-diagonal ``extra`` ``(N, 3, 3)`` if given (friction), across ``normals`` if given
        (see :func:`~.block_cg.block_cg`), and whether the matrix was found positive definite
        along the way (CG only; a direct solve says yes)."""
        blocked = same_blocks(stiffness, damping) and rhs.size % 3 == 0
        if not blocked:
            matrix = mass_minus(system.mass, damping, stiffness, h, rhs.shape)
            return linear_solve(system, matrix, rhs), True
        data = np.empty_like(stiffness.data)
        damping_data = stiffness.data[:0] if damping is None else damping.data
        newton_blocks(
            stiffness.indptr, stiffness.indices, stiffness.data, damping_data,
            mass.reshape(-1, 3), h, data,
        )  # fmt: skip
        if extra is not None:
            _add_diagonal(stiffness.indptr, stiffness.indices, data, extra)
        if self.linear_solver == "direct":
            import scipy.sparse as sp

            matrix = sp.bsr_matrix((data, stiffness.indices, stiffness.indptr), stiffness.shape)
            if normals is not None:
                # S A S + (I − S), S the projection across the normals: the held components
                # of d solve to 0, the free ones see A restricted to them.
                across = np.eye(3) - normals[:, :, None] * normals[:, None, :]
                rows = np.arange(normals.shape[0] + 1, dtype=np.int32)
                s = sp.bsr_matrix((across, rows[:-1], rows), stiffness.shape)
                matrix = s @ matrix @ s + sp.identity(rhs.size) - s
            return linear_solve(system, matrix.tocsc(), rhs), True
        system.counters.linear_solves += 1
        direction = np.zeros((rhs.size // 3, 3))
        iterations, _, positive = block_cg(
            stiffness.indptr,
            stiffness.indices,
            data,
            rhs.reshape(-1, 3),
            direction,
            self.cg_rtol,
            self.cg_max_iterations,
            normals,
            self._multigrid(system, stiffness.indptr, stiffness.indices, data),
        )
        system.counters.krylov_iterations += iterations
        # Not converged within the iterations, or stopped by negative curvature: the iterate is
        # still a descent direction from CG (Newton's line search and stopping rule judge it).
        return direction.reshape(rhs.shape), positive

    def _multigrid(
        self, system: System, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray
    ) -> Any:
        """The multigrid cycle of the Newton matrix (``None`` for block Jacobi); the levels
        are built once per pattern and run, and kept in the run's workspace."""
        if self.preconditioner != "multigrid":
            return None
        levels = system.workspace.get(self, _Levels)
        if levels.hierarchy is None or not levels.hierarchy.matches(indptr, indices):
            levels.hierarchy = Hierarchy(indptr, indices)
        return levels.hierarchy.cycle(data)


class _Levels:
    """A run's multigrid hierarchy, for the pattern of its latest Newton matrix."""

    __slots__ = ("hierarchy",)

    def __init__(self) -> None:
        self.hierarchy: Hierarchy | None = None


def same_blocks(stiffness: Any, damping: Any) -> bool:
    """Both Jacobians block-sparse with 3×3 blocks on one pattern (a scene's particles)."""
    import scipy.sparse as sp

    def blocked(matrix: Any) -> bool:
        return sp.isspmatrix_bsr(matrix) and matrix.blocksize == (3, 3)

    if not blocked(stiffness):
        return False
    return damping is None or (
        blocked(damping)
        and np.array_equal(damping.indptr, stiffness.indptr)
        and np.array_equal(damping.indices, stiffness.indices)
    )


@njit(cache=True, parallel=True)
def _add_diagonal(indptr, indices, data, extra):  # pragma: no cover - compiled
    """``data``'s block ``(r, r)`` += ``extra[r]`` for every block row ``r``."""
    for r in prange(indptr.shape[0] - 1):
        for b in range(indptr[r], indptr[r + 1]):
            if indices[b] == r:
                for a in range(3):
                    for c in range(3):
                        data[b, a, c] += extra[r, a, c]


@njit(cache=True, parallel=True)
def newton_blocks(indptr, indices, k, d, mass, h, out):  # pragma: no cover - compiled
    """``out ← M − h D − h² K`` block by block (``D`` may be empty: no damping)."""
    damped = d.shape[0] > 0
    for r in prange(indptr.shape[0] - 1):
        for b in range(indptr[r], indptr[r + 1]):
            for a in range(3):
                for c in range(3):
                    value = -h * h * k[b, a, c]
                    if damped:
                        value -= h * d[b, a, c]
                    out[b, a, c] = value
            if indices[b] == r:
                for a in range(3):
                    out[b, a, a] += mass[r, a]
