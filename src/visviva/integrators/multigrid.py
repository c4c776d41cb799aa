"""Aggregation multigrid: a preconditioner for CG on 3×3-block Newton matrices whose iteration
count grows more slowly with the resolution than block Jacobi's.

Block-Jacobi CG on a cloth's Newton matrix ``A = M − h D − h² K`` needs iterations in proportion
to the number of points across the cloth: the stiffness over a point's mass grows as N², and
CG must carry each correction across the cloth one block row per iteration. A multigrid cycle
moves it across on coarser copies of the problem instead.

The copies are built from the matrix's pattern alone, once per pattern (plain aggregation, no
geometry): points are grouped greedily into *aggregates* — a point whose neighbours are all
unclaimed takes them as its aggregate, leftovers join a neighbouring aggregate (Vaněk, Mandel &
Brezina 1996, without their prolongation smoothing: Notay 2010's *plain* aggregation). Each
aggregate is one point of the next level; the prolongation ``P`` copies an aggregate's
correction to its points (per component, so a 3×3 block stays a 3×3 block), and the coarse
matrix is Galerkin's ``Pᵀ A P``: the sum of the blocks between two aggregates. Levels are
aggregated again until at most :data:`COARSEST` points are left, which are solved exactly (a
dense Cholesky factor; where aggregation stalls above that, one more sweep). On every Newton
iteration only the sums are redone (one pass over the blocks per level) and the coarsest level
refactorized.

One application of the preconditioner is a V(1, 1) cycle: on each level a damped block-Jacobi
sweep (``z ← ω D⁻¹ r``), the residual restricted to the next level, the coarse correction
prolongated, and a second sweep. Pre- and post-sweeps are the same symmetric operator, so the
cycle is symmetric, and positive definite where ``A`` is (the damping ``ω`` keeps each sweep a
contraction): what CG requires of a preconditioner. Points no force couples to another (lone
particles) are left out of the coarse levels: their sweeps alone solve their rows.

Measured on the implicit cloth benchmark's Newton matrices (64 × 64 points, h = 1/60 s): 8–30
CG iterations per solve to a relative residual of 1e-2, where block Jacobi takes 23–241; each
iteration costs about three products with ``A`` instead of one. The count still grows with the
resolution (on a jittered spring grid to 1e-8: 71, 99, 200, 328 iterations at 16², 32², 64²,
128², against block Jacobi's 253, 514, 1022, 1765): the coarse spaces hold each aggregate's
translations but not its rotations, which a membrane of springs resists only through its
stiff in-plane springs. Smoothed aggregation with the six rigid modes per aggregate (Vaněk et
al.; Tamstorf et al. for cloth) removes that growth, at the price of 6×6 coarse blocks and a
sparse matrix product per Newton iteration.

References:
    P. Vaněk, J. Mandel, M. Brezina, "Algebraic multigrid by smoothed aggregation for second
    and fourth order elliptic problems", Computing 56 (1996) 179–196 (aggregation).
    Y. Notay, "An aggregation-based algebraic multigrid method", Electron. Trans. Numer. Anal.
    37 (2010) 123–146 (plain aggregation as a CG preconditioner).
    R. Tamstorf, T. Jones, S. F. McCormick, "Smoothed aggregation multigrid for cloth
    simulation", ACM Trans. Graph. 34(6) (2015) 245 (multigrid-preconditioned CG for cloth).
    W. L. Briggs, V. E. Henson, S. F. McCormick, *A Multigrid Tutorial*, 2nd ed., SIAM 2000.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .._blas import one_blas_thread
from .bsr import block_product, diagonal_inverse

__all__ = ["Cycle", "Hierarchy", "jacobi", "vcycle"]

#: One array per level, finest first.
Levels = tuple[np.ndarray, ...]

#: Points at the coarsest level at most (solved there by a dense Cholesky factor: ≤ 384 rows).
COARSEST = 128
#: Damping of the block-Jacobi sweeps (Gershgorin bounds ``ρ(D⁻¹A)`` by 2 for the block
#: diagonally dominant Newton matrices of springs: ω·ρ < 2 keeps the sweeps contractions).
DAMPING = 0.6
#: Coarsening stops where a level would keep more than this fraction of its points.
SLOW_COARSENING = 0.6


class Hierarchy:
    """The levels of one block pattern (see the module docstring), built once.

    Args:
        indptr, indices: The fine matrix's BSR pattern (3×3 blocks).

    Attributes:
        levels: Per coarse level ``(aggregate, indptr, indices, map)``: ``aggregate[i]`` the
            coarse point of fine point ``i`` (−1: left out), the coarse pattern, and
            ``map[b]`` the coarse block that fine block ``b`` adds to (−1: none).
    """

    def __init__(self, indptr: np.ndarray, indices: np.ndarray) -> None:
        self.indptr, self.indices = indptr, indices
        # One integer type on every level: the kernels take the levels as tuples of arrays of
        # one type (not typed lists, whose methods Numba compiles anew in every process).
        self._pattern = (indptr.astype(np.int64), indices.astype(np.int64))
        self.levels: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
        rows, columns = self._pattern
        while True:
            count = rows.shape[0] - 1
            if count <= COARSEST:
                break
            aggregate = np.empty(count, dtype=np.int64)
            coarse = _aggregate(rows, columns, aggregate)
            if coarse == 0 or coarse > SLOW_COARSENING * count:
                break
            level = _coarse_pattern(rows, columns, aggregate, coarse)
            self.levels.append(level)
            rows, columns = level[1], level[2]
        # What every cycle of this pattern shares, made once: the levels' patterns and the
        # V-cycle's work space (scratch: nothing in it outlives a cycle's application).
        self._rows = (self._pattern[0], *(level[1] for level in self.levels))
        self._columns = (self._pattern[1], *(level[2] for level in self.levels))
        self._work = _work_space(self._rows)

    def matches(self, indptr: np.ndarray, indices: np.ndarray) -> bool:
        """Whether this hierarchy was built for that pattern."""
        return (indptr is self.indptr and indices is self.indices) or (
            np.array_equal(indptr, self.indptr) and np.array_equal(indices, self.indices)
        )

    def cycle(self, data: np.ndarray) -> Cycle:
        """The V-cycle for the matrix with blocks ``data`` on this pattern — or plain block
        Jacobi if the coarsest level is not positive definite (then neither is the matrix, and
        CG is to find a direction of negative curvature, not to converge fast)."""
        indptr, indices = self._rows, self._columns
        blocks, aggregates = [data], []
        for level, (aggregate, rows, columns, block_map) in enumerate(self.levels):
            if level == 0:
                # Points held by pins have rows without coupling: keep them out.
                aggregate, block_map = _without_loose(
                    indptr[0], indices[0], data, aggregate, block_map
                )
            coarse = np.empty((columns.shape[0], 3, 3))
            _sum_blocks(block_map, blocks[-1], rows, columns, coarse)
            blocks.append(coarse)
            aggregates.append(aggregate)
        inverses = []
        for rows, columns, values in zip(indptr, indices, blocks, strict=True):
            inverse = np.empty((rows.shape[0] - 1, 3, 3))
            diagonal_inverse(rows, columns, values, inverse)
            inverses.append(inverse)
        factor = np.empty((0, 0))  # the coarsest level too large to solve: one sweep there
        if indptr[-1].shape[0] - 1 <= COARSEST:
            try:
                with one_blas_thread():  # ≤ 384 rows: threads only wait on each other
                    factor = np.linalg.cholesky(_dense(indptr[-1], indices[-1], blocks[-1]))
            except np.linalg.LinAlgError:
                return jacobi(self.indptr, self.indices, data)
        return Cycle(
            indptr, indices, tuple(blocks), tuple(inverses), aggregates, factor, self._work
        )


class Cycle:
    """One matrix's V-cycle: per level its pattern, blocks and inverted diagonal blocks, the
    aggregates between levels, and the coarsest level's Cholesky factor (empty: a sweep
    there), with work space — as the tuple :attr:`arrays` that :func:`vcycle` takes."""

    def __init__(
        self,
        indptr: Levels,
        indices: Levels,
        blocks: Levels,
        inverses: Levels,
        aggregates: list[np.ndarray],
        factor: np.ndarray,
        work: tuple[Levels, Levels, Levels],
    ) -> None:
        self.levels = len(aggregates)
        # A tuple of one type for the kernels, even without coarse levels (never read then).
        between = tuple(aggregates) or (np.empty(0, dtype=np.int64),)
        self.arrays = (self.levels, indptr, indices, blocks, inverses, between, factor, *work)

    def apply(self, r: np.ndarray, z: np.ndarray) -> None:
        """``z ← B r`` (``(N, 3)`` each), ``B`` the cycle's approximate inverse of ``A``."""
        vcycle(*self.arrays, r, z)


def jacobi(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray) -> Cycle:
    """Block Jacobi as a cycle without coarse levels: ``B = ω D⁻¹`` (``ω`` does not change CG's
    iterates)."""
    inverse = np.empty((indptr.shape[0] - 1, 3, 3))
    diagonal_inverse(indptr, indices, data, inverse)
    rows, columns = (indptr.astype(np.int64),), (indices.astype(np.int64),)
    return Cycle(rows, columns, (data,), (inverse,), [], np.empty((0, 0)), _work_space(rows))


def _work_space(indptr: Levels) -> tuple[Levels, Levels, Levels]:
    """The V-cycle's residuals, corrections and scratch, ``(n_l, 3)`` per level."""
    return tuple(tuple(np.empty((rows.shape[0] - 1, 3)) for rows in indptr) for _ in range(3))  # type: ignore[return-value]


@njit(cache=True)
def _aggregate(indptr, indices, aggregate):  # pragma: no cover - compiled
    """Greedy plain aggregation of the pattern's graph into ``aggregate`` (−1 for points with
    no neighbour); returns the number of aggregates."""
    count = indptr.shape[0] - 1
    aggregate[:] = -1
    lonely = np.zeros(count, dtype=np.bool_)
    formed = 0
    # 1: a point whose neighbours are all unclaimed takes them.
    for i in range(count):
        if aggregate[i] >= 0:
            continue
        free, neighbours = True, 0
        for b in range(indptr[i], indptr[i + 1]):
            j = indices[b]
            if j != i:
                neighbours += 1
                if aggregate[j] >= 0:
                    free = False
        if neighbours == 0:
            lonely[i] = True
            continue
        if free:
            aggregate[i] = formed
            for b in range(indptr[i], indptr[i + 1]):
                aggregate[indices[b]] = formed
            formed += 1
    # 2: the others join the aggregate of a neighbour from pass 1 (or start their own).
    claimed = aggregate.copy()
    for i in range(count):
        if aggregate[i] >= 0 or lonely[i]:
            continue
        for b in range(indptr[i], indptr[i + 1]):
            j = indices[b]
            if claimed[j] >= 0:
                aggregate[i] = claimed[j]
                break
        if aggregate[i] < 0:
            aggregate[i] = formed
            for b in range(indptr[i], indptr[i + 1]):
                j = indices[b]
                if aggregate[j] < 0 and not lonely[j]:
                    aggregate[j] = formed
            formed += 1
    return formed


def _coarse_pattern(
    indptr: np.ndarray, indices: np.ndarray, aggregate: np.ndarray, coarse: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The next level from the aggregates: ``(aggregate, indptr, indices, map)`` (see
    :class:`Hierarchy`), the coarse blocks sorted by row, then column."""
    rows = np.repeat(np.arange(indptr.shape[0] - 1), np.diff(indptr))
    first, second = aggregate[rows], aggregate[indices]
    kept = (first >= 0) & (second >= 0)
    keys = first * coarse + second
    unique, inverse = np.unique(keys[kept], return_inverse=True)
    block_map = np.full(indices.shape[0], -1, dtype=np.int64)
    block_map[kept] = inverse
    coarse_rows = unique // coarse
    coarse_indptr = np.zeros(coarse + 1, dtype=np.int64)
    np.cumsum(np.bincount(coarse_rows, minlength=coarse), out=coarse_indptr[1:])
    return aggregate, coarse_indptr, (unique % coarse).astype(np.int64), block_map


@njit(cache=True)
def _without_loose(indptr, indices, data, aggregate, block_map):  # pragma: no cover - compiled
    """``aggregate`` and ``block_map`` without the points whose rows couple to no other point
    in this matrix (pinned points: their off-diagonal blocks are zero), as copies. Their own
    rows solve them exactly in the sweeps; in an aggregate, the coarse correction would move
    them."""
    aggregate, block_map = aggregate.copy(), block_map.copy()
    count = indptr.shape[0] - 1
    loose = np.zeros(count, dtype=np.bool_)
    for r in range(count):
        loose[r] = True
        for b in range(indptr[r], indptr[r + 1]):
            if indices[b] != r:
                for a in range(3):
                    for d in range(3):
                        if data[b, a, d] != 0.0:
                            loose[r] = False
        if loose[r]:
            aggregate[r] = -1
    for r in range(count):
        for b in range(indptr[r], indptr[r + 1]):
            if loose[r] or loose[indices[b]]:
                block_map[b] = -1
    return aggregate, block_map


@njit(cache=True)
def _sum_blocks(block_map, fine, indptr, indices, coarse):  # pragma: no cover - compiled
    """``coarse`` ← Galerkin's ``Pᵀ A P`` for plain aggregation: each coarse block the sum of
    the fine blocks ``map`` sends to it; an aggregate of loose points only (no blocks) gets
    the identity as its diagonal block, which leaves it at zero."""
    coarse[:] = 0.0
    for b in range(block_map.shape[0]):
        c = block_map[b]
        if c >= 0:
            for a in range(3):
                for d in range(3):
                    coarse[c, a, d] += fine[b, a, d]
    for r in range(indptr.shape[0] - 1):
        for b in range(indptr[r], indptr[r + 1]):
            if indices[b] == r and not np.any(coarse[b]):
                for a in range(3):
                    coarse[b, a, a] = 1.0


@njit(cache=True)
def _dense(indptr, indices, data):  # pragma: no cover - compiled
    """The BSR matrix as a dense ``(3n, 3n)`` array."""
    n = indptr.shape[0] - 1
    out = np.zeros((3 * n, 3 * n))
    for r in range(n):
        for b in range(indptr[r], indptr[r + 1]):
            c = indices[b]
            for a in range(3):
                for d in range(3):
                    out[3 * r + a, 3 * c + d] = data[b, a, d]
    return out


@njit(cache=True, parallel=True)
def _sweep(inverse, r, ar, z, add):  # pragma: no cover - compiled
    """One damped block-Jacobi sweep: ``z ← ω D⁻¹ (r − A z)`` (``add``: ``z +=``, with ``ar``
    = ``A z``; else ``z ←  ω D⁻¹ r`` from zero and ``ar`` unused)."""
    for i in prange(r.shape[0]):
        r0, r1, r2 = r[i, 0], r[i, 1], r[i, 2]
        if add:
            r0, r1, r2 = r0 - ar[i, 0], r1 - ar[i, 1], r2 - ar[i, 2]
        for a in range(3):
            row = inverse[i, a]
            value = DAMPING * (row[0] * r0 + row[1] * r1 + row[2] * r2)
            z[i, a] = z[i, a] + value if add else value


@njit(cache=True)
def _restrict(aggregate, r, az, coarse):  # pragma: no cover - compiled
    """``coarse`` ← ``Pᵀ (r − A z)``: the residual summed over each aggregate."""
    coarse[:] = 0.0
    for i in range(aggregate.shape[0]):
        c = aggregate[i]
        if c >= 0:
            for a in range(3):
                coarse[c, a] += r[i, a] - az[i, a]


@njit(cache=True, parallel=True)
def _prolong(aggregate, coarse, z):  # pragma: no cover - compiled
    """``z += P e``: each point gets its aggregate's correction."""
    for i in prange(aggregate.shape[0]):
        c = aggregate[i]
        if c >= 0:
            for a in range(3):
                z[i, a] += coarse[c, a]


@njit(cache=True)
def _cholesky_solve(factor, r, z):  # pragma: no cover - compiled
    """``z ← (L Lᵀ)⁻¹ r`` by two triangular sweeps (``r``, ``z`` ``(n, 3)``, flattened row-wise
    as the dense matrix's rows)."""
    n = factor.shape[0]
    y = np.empty(n)
    for i in range(n):
        total = r[i // 3, i % 3]
        for k in range(i):
            total -= factor[i, k] * y[k]
        y[i] = total / factor[i, i]
    for i in range(n - 1, -1, -1):
        total = y[i]
        for k in range(i + 1, n):
            total -= factor[k, i] * z[k // 3, k % 3]
        z[i // 3, i % 3] = total / factor[i, i]


@njit(cache=True)
def vcycle(
    levels,
    indptr,
    indices,
    blocks,
    inverses,
    aggregates,
    factor,
    residuals,
    corrections,
    scratch,
    r,
    z,
):  # pragma: no cover - compiled
    """``z ← B r``, one V(1, 1) cycle (see the module docstring) over ``levels`` coarse levels;
    the tuples hold each level's arrays, finest first, and ``residuals``/``corrections``/
    ``scratch`` are work space."""
    residuals[0][:] = r
    for level in range(levels):
        rl, zl, work = residuals[level], corrections[level], scratch[level]
        _sweep(inverses[level], rl, rl, zl, False)
        block_product(indptr[level], indices[level], blocks[level], zl, work)
        _restrict(aggregates[level], rl, work, residuals[level + 1])
    if factor.shape[0]:
        _cholesky_solve(factor, residuals[levels], corrections[levels])
    else:
        _sweep(inverses[levels], residuals[levels], residuals[levels], corrections[levels], False)
    for level in range(levels - 1, -1, -1):
        rl, zl, work = residuals[level], corrections[level], scratch[level]
        _prolong(aggregates[level], corrections[level + 1], zl)
        block_product(indptr[level], indices[level], blocks[level], zl, work)
        _sweep(inverses[level], rl, work, zl, True)
    z[:] = corrections[0]
