"""The sum of a scene's particle forces, and its sparse Jacobians on a pattern built once.

:class:`ForceSum` adds every force into one ``(N, 3)`` array and assembles the forces'
3×3 Jacobian blocks into block-sparse matrices ``∂F/∂x`` and ``∂F/∂v`` (``3N × 3N``, BSR with
3×3 blocks). The union of the forces' block patterns is sorted and indexed when the sum is
built — once per topology — so each Newton iteration only refills the block values
(NOTES.md: refilling a fixed pattern is 3.5× faster than rebuilding it) and nothing of size
``N²`` is ever allocated.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numba import njit, prange

from ..ode.workspace import Workspace
from .base import Force, JacobianForm

__all__ = ["ForceSum"]


class ForceSum:
    """Every particle force of a scene, summed.

    Args:
        forces: The forces.
        count: Number of particles ``N``.
        work: The run's storage, which the forces keep their scratch in (default: a fresh
            one). A sum belongs to one run: its Jacobians' block values are scratch too.

    Attributes:
        forces: The forces, in order.
        velocity_dependent: True if any force depends on the velocities.
        conservative: True if every force is ``−∇U`` of the energy it reports.
        gradient_form: True if the sum is ``F(x, v) = −∇U(x) + D(x) v`` with ``D = ∂F/∂v``
            symmetric: every force conservative, or damped linearly in the velocities (a force
            says so with ``linear_damping``). Backward Euler's step then minimizes an energy.
        has_jacobian: True if every force gives its Jacobian blocks.
        blocks: Number of distinct 3×3 blocks in the Jacobians' pattern, which holds every
            diagonal block ``(i, i)`` (a Newton matrix adds the masses there).
        indptr, indices: The pattern in BSR form (block rows ``N``).
        diagonal: ``(N,)`` the index of block ``(i, i)`` among the blocks.
    """

    def __init__(self, forces: Sequence[Force], count: int, work: Workspace | None = None) -> None:
        self.forces = tuple(forces)
        self.count = count
        self.work = work if work is not None else Workspace()
        self.velocity_dependent = any(f.velocity_dependent for f in self.forces)
        self.conservative = all(f.conservative for f in self.forces)
        self.gradient_form = all(f.conservative or f.linear_damping for f in self.forces)
        patterns = [f.jacobian_blocks() for f in self.forces]
        self.has_jacobian = all(p is not None for p in patterns)
        self.blocks = 0
        if self.has_jacobian:
            self._build_pattern([p for p in patterns if p is not None])

    def _build_pattern(self, patterns: list[tuple[np.ndarray, np.ndarray]]) -> None:
        every = np.arange(self.count, dtype=np.int64)
        rows = np.concatenate([p[0] for p in patterns] + [every])
        cols = np.concatenate([p[1] for p in patterns] + [every])
        keys, slots = np.unique(rows * self.count + cols, return_inverse=True)
        block_rows, self.indices = np.divmod(keys, self.count)
        self.indices = self.indices.astype(np.int32)
        self.indptr = np.searchsorted(block_rows, np.arange(self.count + 1)).astype(np.int32)
        self.diagonal = slots[-self.count :] if self.count else np.zeros(0, np.int64)
        # The forces fill their blocks side by side in one array (``_local``); each distinct
        # block is the sum of its entries there, listed in CSR form for a parallel gather.
        filled = slots[: slots.shape[0] - self.count]
        self._bounds = np.cumsum([0] + [p[0].shape[0] for p in patterns])
        self._order = np.argsort(filled, kind="stable").astype(np.int64)
        self._start = np.searchsorted(filled[self._order], np.arange(keys.shape[0] + 1))
        self._local = np.empty((2, filled.shape[0], 3, 3))
        self.blocks = int(keys.shape[0])

    def accumulate(
        self, t: float, x: np.ndarray, v: np.ndarray, out: np.ndarray, work: Workspace | None = None
    ) -> None:
        """Add every force [N] into ``out`` ``(N, 3)``."""
        for force in self.forces:
            force.accumulate(t, x, v, out, self.work)

    def potential(self, t: float, x: np.ndarray, alive: np.ndarray | None = None) -> float:
        """The forces' potential energy [J] (over the particles ``alive``, if given)."""
        return sum((f.potential(t, x, alive) for f in self.forces), 0.0)

    def jacobian(
        self, t: float, x: np.ndarray, v: np.ndarray, form: JacobianForm = "exact"
    ) -> tuple[Any, Any]:
        """``(∂F/∂x, ∂F/∂v)`` as ``3N × 3N`` block-sparse matrices (BSR, 3×3 blocks, on the
        pattern :attr:`indptr`, :attr:`indices`; ``∂F/∂v`` is ``None`` if no force depends
        on velocity), each force's in the ``form`` asked for (:data:`~.base.JacobianForm`).

        Raises:
            ValueError: If a force has no analytic Jacobian (check :attr:`has_jacobian`).
        """
        import scipy.sparse as sp

        if not self.has_jacobian:
            raise ValueError("a force of this scene has no analytic Jacobian")
        local_x, local_v = self._local
        local_x.fill(0.0)
        local_v.fill(0.0)
        for force, a, b in zip(self.forces, self._bounds[:-1], self._bounds[1:], strict=True):
            force.add_jacobian(t, x, v, local_x[a:b], local_v[a:b], form)
        shape = (3 * self.count, 3 * self.count)
        matrices = []
        for local in self._local[: 2 if self.velocity_dependent else 1]:
            blocks = np.empty((self.blocks, 3, 3))
            _sum_blocks(self._start, self._order, local, blocks)
            matrices.append(sp.bsr_matrix((blocks, self.indices, self.indptr), shape=shape))
        return matrices[0], (matrices[1] if self.velocity_dependent else None)


@njit(cache=True, parallel=True)
def _sum_blocks(start, order, local, out):  # pragma: no cover - compiled
    """``out[k] ← Σ local[order[j]]`` for ``j`` in ``start[k] : start[k + 1]``."""
    for k in prange(out.shape[0]):
        for a in range(3):
            for b in range(3):
                out[k, a, b] = 0.0
        for j in range(start[k], start[k + 1]):
            e = order[j]
            for a in range(3):
                for b in range(3):
                    out[k, a, b] += local[e, a, b]
