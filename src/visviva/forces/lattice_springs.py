"""Springs on a regular lattice, summed at each point without index arrays (a stencil).

A cloth grid or a soft lattice (:mod:`visviva.deformables.topology`) joins every lattice point
``p`` to the point ``p + o`` for each of a few fixed offsets ``o`` (structural, shear, bend,
diagonal), with one stiffness and one damping per offset. The general spring force
(:func:`~visviva.forces.springs.spring_forces`) reads each spring's two ends through index
arrays, writes each spring's force, and each particle then sums its springs' forces through
its CSR lists: random reads that keep a core near 2e8 springs/s (NOTES.md). Here each point
instead sums, offset by offset, the forces of its spring to ``p + o`` and of its spring from
``p − o``, reading both ends through contiguous slices of a lattice row: no index is read,
no per-spring force is stored, and the compiler vectorizes the inner loop (eight springs an
instruction with AVX-512). Each spring is computed twice, once from each end, which costs
less than the traffic it saves: on ``benchmarks/bench_cloth.py``'s 256² cloth (390,658
springs, 2 threads) the stencil took 0.43 ms, the spring pass and the gather 1.5 ms. The
force on ``p`` from its
neighbour ``q`` is that of :mod:`~visviva.forces.springs` seen from ``p`` as the first end:

    f = (k (l − L) + c (w · u)) u,   d = x_q − x_p,  l = |d|,  u = d / l,  w = v_q − v_p

so the two ends of a spring get ``+f`` and ``−f`` to round-off (the same operations on the
same numbers, mirrored), and the sum over a point's springs differs from the CSR gather's only
in its order. ``tests/test_lattice_springs.py`` checks it against :class:`Springs` on cloth
grids and soft lattices, edges and corners included.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit, prange

__all__ = ["SpringStencil"]

#: Rows of a lattice one thread takes at a time (its three row buffers are made once a chunk).
_ROWS_A_CHUNK = 16


@dataclass(frozen=True)
class SpringStencil:
    """The springs of a lattice as offsets (see the module docstring).

    Attributes:
        shape: ``(n0, n1, n2)`` points along each axis, ``n0`` the fastest: point ``(i, j, k)``
            is particle ``start + (k n1 + j) n0 + i`` (a cloth grid has ``n2 = 1``).
        start: The particle index of point ``(0, 0, 0)``.
        offsets: ``(F, 3)`` int64, each offset ``(di, dj, dk)`` that springs join.
        stiffness: ``(F,)`` k of the springs of each offset [N/m].
        damping: ``(F,)`` c of the springs of each offset [N·s/m].
        rest_length: ``(F, n0 n1 n2)`` the rest length [m] of the spring from each point along
            each offset (0 where the point has none).
    """

    shape: tuple[int, int, int]
    start: int
    offsets: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    rest_length: np.ndarray

    @classmethod
    def of(
        cls,
        pairs: np.ndarray,
        rest_length: np.ndarray,
        stiffness: np.ndarray,
        damping: np.ndarray,
        shape: tuple[int, ...],
        start: int,
    ) -> SpringStencil | None:
        """The stencil of springs ``pairs`` ``(S, 2)`` (with ``(S,)`` rest lengths, stiffness
        and damping) among the points of a lattice of ``shape`` (two or three sizes, fastest
        first) whose first point is particle ``start``; ``None`` unless they are exactly such
        springs: each joins two points of the lattice, and those of each offset join every
        point that has a partner at that offset, once, with one stiffness and one damping."""
        n0, n1, n2 = (*shape, 1)[:3]
        count = n0 * n1 * n2
        local = np.asarray(pairs, dtype=np.int64) - start
        if local.size == 0 or local.min() < 0 or local.max() >= count:
            return None
        k, j, i = np.unravel_index(local, (n2, n1, n0))
        offset = np.stack([i[:, 1] - i[:, 0], j[:, 1] - j[:, 0], k[:, 1] - k[:, 0]], axis=1)
        # Each offset as one number, to find the families by a sort of integers (sorting the
        # rows of ``offset`` takes seconds for a million springs).
        sizes = 2 * np.array([n0, n1, n2]) - 1
        code = np.ravel_multi_index((offset + [n0 - 1, n1 - 1, n2 - 1]).T, sizes)
        codes, family = np.unique(code, return_inverse=True)
        offsets = np.stack(np.unravel_index(codes, sizes), axis=1) - [n0 - 1, n1 - 1, n2 - 1]
        rest = np.zeros((codes.shape[0], count))
        ks, cs = np.empty(codes.shape[0]), np.empty(codes.shape[0])
        for f, o in enumerate(offsets):
            members = np.flatnonzero(family == f)
            first = local[members, 0]
            partnered = np.prod([n - abs(d) for n, d in zip((n0, n1, n2), o, strict=True)])
            if (
                members.shape[0] != partnered
                or np.bincount(first, minlength=count).max() > 1
                or np.ptp(stiffness[members]) != 0.0
                or np.ptp(damping[members]) != 0.0
            ):
                return None
            rest[f, first] = rest_length[members]
            ks[f], cs[f] = stiffness[members[0]], damping[members[0]]
        return cls((n0, n1, n2), start, offsets.astype(np.int64), ks, cs, rest)

    @property
    def points(self) -> int:
        """How many points the lattice has."""
        return int(self.rest_length.shape[1])

    def forces(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        """``out[:, p]`` ← the springs' force [N] on each lattice point ``p`` (``(3, n)``,
        the lattice's points only), from positions ``x`` and velocities ``v`` ``(3, N)`` [m],
        [m/s] of every particle, one row per component."""
        n0, n1, n2 = self.shape
        _stencil_forces(
            *x, *v, self.start, n0, n1, n2, self.offsets, self.stiffness, self.damping,
            self.rest_length, *out,
        )  # fmt: skip


# fmt: off
@njit(cache=True, parallel=True, error_model="numpy")
def _stencil_forces(
    x, y, z, vx, vy, vz, start, n0, n1, n2, offsets, k, c, rest, fx, fy, fz,
):  # pragma: no cover - compiled
    """``(fx, fy, fz)[p]``: the force on lattice point ``p`` of its springs [N] (see the
    module docstring), rows of ``n0`` points at a time."""
    # fmt: on
    rows = n1 * n2
    chunks = (rows + _ROWS_A_CHUNK - 1) // _ROWS_A_CHUNK
    for chunk in prange(chunks):
        # Row buffers made here, not passed in: the compiler then knows they overlap no
        # input, and vectorizes the loop without checks at run time.
        sx, sy, sz = np.empty(n0), np.empty(n0), np.empty(n0)
        for row in range(chunk * _ROWS_A_CHUNK, min(rows, (chunk + 1) * _ROWS_A_CHUNK)):
            j, kk = row % n1, row // n1
            base = start + row * n0
            sx[:] = 0.0
            sy[:] = 0.0
            sz[:] = 0.0
            for f in range(offsets.shape[0]):
                kf, cf = k[f], c[f]
                for side in (1, -1):  # the spring from p to p + o, then from p − o to p
                    di, dj, dk = side * offsets[f, 0], side * offsets[f, 1], side * offsets[f, 2]
                    if not (0 <= j + dj < n1 and 0 <= kk + dk < n2):
                        continue
                    lo, hi = max(0, -di), min(n0, n0 - di)
                    if hi <= lo:
                        continue
                    p = base + lo  # the first point of the run, and its neighbour q
                    q = p + di + n0 * (dj + n1 * dk)
                    first = (p if side == 1 else q) - start  # the spring's first end
                    m = hi - lo
                    px, py, pz = x[p:p + m], y[p:p + m], z[p:p + m]
                    pvx, pvy, pvz = vx[p:p + m], vy[p:p + m], vz[p:p + m]
                    qx, qy, qz = x[q:q + m], y[q:q + m], z[q:q + m]
                    qvx, qvy, qvz = vx[q:q + m], vy[q:q + m], vz[q:q + m]
                    length = rest[f, first:first + m]
                    for a in range(m):
                        dx, dy, dz = qx[a] - px[a], qy[a] - py[a], qz[a] - pz[a]
                        norm = np.sqrt(dx * dx + dy * dy + dz * dz)
                        inverse = 1.0 / norm
                        ux, uy, uz = dx * inverse, dy * inverse, dz * inverse
                        rate = (
                            (qvx[a] - pvx[a]) * ux + (qvy[a] - pvy[a]) * uy
                            + (qvz[a] - pvz[a]) * uz
                        )
                        magnitude = kf * (norm - length[a]) + cf * rate
                        sx[lo + a] += magnitude * ux
                        sy[lo + a] += magnitude * uy
                        sz[lo + a] += magnitude * uz
            out = base - start
            fx[out:out + n0] = sx
            fy[out:out + n0] = sy
            fz[out:out + n0] = sz
