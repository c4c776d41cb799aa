"""Conjugate gradients on block-sparse matrices of 3×3 blocks: the linear solver of implicit
steps on particle systems.

A scene's Newton matrix ``A = M − h D − h² K`` has one 3×3 block per pair of particles that a
force couples (BSR storage, :mod:`.bsr`). Where it is symmetric positive definite — springs with
their stiffness projected (see :meth:`~visviva.forces.Springs.add_definite_jacobian`) — CG
solves it with one matrix–vector product per iteration and ``O(N)`` memory. The preconditioner
is an aggregation multigrid cycle (:mod:`.multigrid`), or the inverted diagonal blocks alone
(block Jacobi: which removes the spread of the masses and of each particle's own stiffness,
but not the coupling across a stiff cloth).

A direction of non-positive curvature (``pᵀAp ≤ 0``: the matrix is not positive definite) ends
the iteration with the iterate so far — the truncated-Newton rule, so an unprojected indefinite
matrix still gives a usable step — and says so.

References:
    D. Baraff, A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998, §5.3 (filtering
    constrained particles' directions out of CG).
    U. M. Ascher, E. Boxerman, "On the modified conjugate gradient method in cloth simulation",
    The Visual Computer 19 (2003) 526–531.
    M. R. Hestenes, E. Stiefel, "Methods of conjugate gradients for solving linear systems",
    J. Res. Nat. Bur. Standards 49 (1952) 409–436.
    J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006, §5.1 and §7.1.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .bsr import block_product
from .multigrid import Cycle, jacobi, vcycle

__all__ = ["block_cg"]


@njit(cache=True, parallel=True)
def _filter(normals, r):  # pragma: no cover - compiled
    """``r_i ← (I − n_i n_iᵀ) r_i`` where row ``i`` of ``normals`` is a unit normal (rows of
    zeros leave ``r_i`` as it is)."""
    for i in prange(r.shape[0]):
        n0, n1, n2 = normals[i, 0], normals[i, 1], normals[i, 2]
        along = r[i, 0] * n0 + r[i, 1] * n1 + r[i, 2] * n2
        r[i, 0] -= along * n0
        r[i, 1] -= along * n1
        r[i, 2] -= along * n2


@njit(cache=True, parallel=True)
def _dot(a, b):  # pragma: no cover - compiled
    total = 0.0
    for i in prange(a.shape[0]):
        total += a[i, 0] * b[i, 0] + a[i, 1] * b[i, 1] + a[i, 2] * b[i, 2]
    return total


@njit(cache=True, parallel=True)
def _axpy_pair(alpha, p, ap, x, r):  # pragma: no cover - compiled
    """``x += α p``, ``r −= α A p``; returns ``r · r``."""
    total = 0.0
    for i in prange(x.shape[0]):
        for a in range(3):
            x[i, a] += alpha * p[i, a]
            value = r[i, a] - alpha * ap[i, a]
            r[i, a] = value
            total += value * value
    return total


@njit(cache=True, parallel=True)
def _new_direction(beta, z, p):  # pragma: no cover - compiled
    """``p ← z + β p``."""
    for i in prange(p.shape[0]):
        for a in range(3):
            p[i, a] = z[i, a] + beta * p[i, a]


@njit(cache=True)
def _precondition(cycle, normals, r, z):  # pragma: no cover - compiled
    """``z ← B r`` (filtered across ``normals`` if any); returns ``r · z``."""
    vcycle(*cycle, r, z)
    if normals.shape[0] > 0:
        _filter(normals, z)
    return _dot(r, z)


@njit(cache=True)
def _cg(indptr, indices, data, cycle, normals, b, x, rtol, max_iterations):  # pragma: no cover
    rows = b.shape[0]
    filtered = normals.shape[0] > 0
    r = np.empty((rows, 3))
    z = np.empty((rows, 3))
    ap = np.empty((rows, 3))
    block_product(indptr, indices, data, x, ap)
    for i in range(rows):
        for a in range(3):
            r[i, a] = b[i, a] - ap[i, a]
    if filtered:
        _filter(normals, r)
    goal = rtol * rtol * _dot(r, r) if filtered else rtol * rtol * _dot(b, b)
    residual = _dot(r, r)
    if residual <= goal or residual == 0.0:
        return 0, True, True
    rz = _precondition(cycle, normals, r, z)
    p = z.copy()
    for iteration in range(1, max_iterations + 1):
        block_product(indptr, indices, data, p, ap)
        if filtered:
            _filter(normals, ap)
        curvature = _dot(p, ap)
        if not curvature > 0.0:
            return iteration, False, False  # not positive definite along p: stop here
        residual = _axpy_pair(rz / curvature, p, ap, x, r)
        if residual <= goal:
            return iteration, True, True
        rz_new = _precondition(cycle, normals, r, z)
        _new_direction(rz_new / rz, z, p)
        rz = rz_new
    return max_iterations, False, True


def block_cg(
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    b: np.ndarray,
    x: np.ndarray,
    rtol: float,
    max_iterations: int,
    normals: np.ndarray | None = None,
    preconditioner: Cycle | None = None,
) -> tuple[int, bool, bool]:
    """Solve ``A x = b`` by preconditioned CG, starting from (and overwriting) ``x``; with
    ``normals``, in the subspace where each row ``x_i`` is orthogonal to ``normals[i]``.

    Args:
        indptr, indices, data: ``A`` in BSR form with 3×3 blocks (``data`` ``(blocks, 3, 3)``),
            symmetric positive definite for CG's guarantees.
        b: ``(rows, 3)`` right-hand side.
        x: ``(rows, 3)`` initial guess (a warm start), the solution on return.
        rtol: Stop when ``‖b − A x‖ ≤ rtol ‖b‖``.
        max_iterations: Iterations allowed.
        normals: ``(rows, 3)`` a unit normal per row whose motion along it is held (zero rows
            are free): CG then solves ``S A S x = S b`` with ``S`` the projection across the
            normals (Baraff & Witkin's filtered PCG for constrained particles), the residual
            measured after filtering. ``x`` must start in that subspace.
        preconditioner: The multigrid cycle of ``A`` (:meth:`.multigrid.Hierarchy.cycle`);
            block Jacobi if not given.

    Returns:
        ``(iterations, converged, positive)``: ``positive`` is false if a direction of
        non-positive curvature stopped the iteration.
    """
    cycle = preconditioner if preconditioner is not None else jacobi(indptr, indices, data)
    held = np.zeros((0, 3)) if normals is None else normals
    return _cg(indptr, indices, data, cycle.arrays, held, b, x, rtol, max_iterations)
