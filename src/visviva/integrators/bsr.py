"""Kernels on block-sparse matrices of 3×3 blocks (BSR storage: ``indptr``, ``indices``,
``data`` of shape ``(blocks, 3, 3)``), the form of a scene's Jacobians and Newton matrices: the
product with a vector and the inverses of the diagonal blocks. Each runs in parallel over block
rows (a thread owns its rows: no races, and the sums run in a fixed order)."""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["block_product", "diagonal_inverse"]


@njit(cache=True, parallel=True)
def block_product(indptr, indices, data, x, out):  # pragma: no cover - compiled
    """``out ← A x`` for ``A`` in BSR form; ``x`` and ``out`` ``(rows, 3)``."""
    for r in prange(indptr.shape[0] - 1):
        s0 = s1 = s2 = 0.0
        for b in range(indptr[r], indptr[r + 1]):
            c = indices[b]
            x0, x1, x2 = x[c, 0], x[c, 1], x[c, 2]
            s0 += data[b, 0, 0] * x0 + data[b, 0, 1] * x1 + data[b, 0, 2] * x2
            s1 += data[b, 1, 0] * x0 + data[b, 1, 1] * x1 + data[b, 1, 2] * x2
            s2 += data[b, 2, 0] * x0 + data[b, 2, 1] * x1 + data[b, 2, 2] * x2
        out[r, 0] = s0
        out[r, 1] = s1
        out[r, 2] = s2


@njit(cache=True, parallel=True)
def diagonal_inverse(indptr, indices, data, out):  # pragma: no cover - compiled
    """``out[r]`` ← the inverse of block ``(r, r)`` (the identity where that block is missing
    or singular: such a row is left unpreconditioned)."""
    for r in prange(indptr.shape[0] - 1):
        for a in range(3):
            for b in range(3):
                out[r, a, b] = 1.0 if a == b else 0.0
        for b in range(indptr[r], indptr[r + 1]):
            if indices[b] == r:
                _invert(data[b], out[r])


@njit(cache=True, inline="always")
def _invert(m, out):  # pragma: no cover - compiled
    """``out ← m⁻¹`` for a 3×3 ``m`` by cofactors; ``out`` unchanged if ``m`` is singular."""
    c00 = m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1]
    c01 = m[1, 2] * m[2, 0] - m[1, 0] * m[2, 2]
    c02 = m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0]
    det = m[0, 0] * c00 + m[0, 1] * c01 + m[0, 2] * c02
    if det == 0.0 or not np.isfinite(det):
        return
    f = 1.0 / det
    out[0, 0] = c00 * f
    out[1, 0] = c01 * f
    out[2, 0] = c02 * f
    out[0, 1] = (m[0, 2] * m[2, 1] - m[0, 1] * m[2, 2]) * f
    out[1, 1] = (m[0, 0] * m[2, 2] - m[0, 2] * m[2, 0]) * f
    out[2, 1] = (m[0, 1] * m[2, 0] - m[0, 0] * m[2, 1]) * f
    out[0, 2] = (m[0, 1] * m[1, 2] - m[0, 2] * m[1, 1]) * f
    out[1, 2] = (m[0, 2] * m[1, 0] - m[0, 0] * m[1, 2]) * f
    out[2, 2] = (m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]) * f
