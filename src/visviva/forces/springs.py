"""Damped springs between particles: the force of every mass-spring deformable.

A spring joins particles ``i`` and ``j`` with rest length ``L`` [m], stiffness ``k`` [N/m] and
damping ``c`` [N·s/m] along the spring (seed 002). With ``d = x_j − x_i``, ``l = |d|``,
``u = d / l`` and ``w = v_j − v_i``,

    f   = (k (l − L) + c (w · u)) u          the force on i; j feels −f       [N]
    U   = ½ k (l − L)²                                                      [J]

so the forces of a spring sum to zero and conserve momentum, and the damper only resists the
rate of stretch (a rigid rotation is not damped). The exact Jacobians, with ``P = I − u uᵀ``
the projection across the spring,

    ∂f/∂x_j = −∂f/∂x_i = K = k u uᵀ + k (1 − L/l) P + (c / l) (u wᵀ P + (w · u) P),
    ∂f/∂v_j = −∂f/∂v_i = D = c u uᵀ,

fill four 3×3 blocks per spring, ``(i, i) = −K``, ``(i, j) = K``, ``(j, i) = K``,
``(j, j) = −K`` (and the same for ``D``), on a pattern fixed when the springs are built. A
compressed spring (``l < L``) makes ``K`` indefinite across the spring: the buckling that
implicit steps handle by projecting it (:meth:`Springs.add_jacobian`'s ``"definite"`` form drops
the negative part, Choi & Ko 2002).

``tests/test_springs.py`` checks every Jacobian against central finite differences of the same
force (compressed springs included) and ``f = −∇U`` without damping.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numba import njit, prange

from ..errors import ModelError
from .base import JacobianForm
from .lattice_springs import SpringStencil

if TYPE_CHECKING:
    from ..ode.workspace import Workspace

__all__ = ["SpringSet", "Springs", "spring_forces", "spring_incidence"]


@dataclass(frozen=True, eq=False)
class SpringSet:
    """Springs' compiled form: what the fused particle step sums them from.

    Attributes:
        pairs: ``(S, 2)`` particle indices.
        rest_length, stiffness, damping: ``(S,)`` each [m], [N/m], [N·s/m].
        stencil: Their stencil, if they are a lattice's (:mod:`.lattice_springs`).
    """

    pairs: np.ndarray
    rest_length: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    stencil: SpringStencil | None


class Springs:
    """Damped springs between particles (see the module docstring).

    Args:
        pairs: ``(S, 2)`` particle indices ``(i, j)`` of each spring, ``i ≠ j``.
        rest_length: ``(S,)`` rest lengths ``L`` [m], > 0.
        stiffness: ``(S,)`` ``k`` [N/m], ≥ 0.
        damping: ``(S,)`` ``c`` [N·s/m], ≥ 0.
        count: Number of particles ``N`` in the scene.
        lattice: ``(shape, start)`` if the springs join the points of a lattice of ``shape``
            (two or three sizes, fastest first) whose first point is particle ``start``: the
            force is then summed by a stencil (:class:`~.lattice_springs.SpringStencil`) if
            the springs are those of a few offsets, each of one stiffness and damping.

    Raises:
        ModelError: Naming the first bad spring: an index out of range, a spring joining a
            particle to itself, a rest length not positive, a negative stiffness or damping.
    """

    conservative: ClassVar[bool] = False
    velocity_dependent: ClassVar[bool] = True
    #: The force is ``−∇U + D v`` with ``D = ∂F/∂v`` symmetric: the damper is linear in the
    #: velocities (see :class:`~visviva.forces.ForceSum`).
    linear_damping: ClassVar[bool] = True

    def __init__(
        self,
        pairs: np.ndarray,
        rest_length: np.ndarray,
        stiffness: np.ndarray,
        damping: np.ndarray,
        count: int,
        lattice: tuple[tuple[int, ...], int] | None = None,
    ) -> None:
        pairs = np.asarray(pairs)
        if pairs.ndim != 2 or pairs.shape[1] != 2 or not np.issubdtype(pairs.dtype, np.integer):
            raise ModelError(f"`pairs` must be an (S, 2) array of particle indices, not {pairs!r}")
        self.pairs = np.ascontiguousarray(pairs, dtype=np.int64)
        springs = self.pairs.shape[0]
        self.rest_length = _per_spring("rest_length", rest_length, springs)
        self.stiffness = _per_spring("stiffness", stiffness, springs)
        self.damping = _per_spring("damping", damping, springs)
        _check(self.pairs, self.rest_length, self.stiffness, self.damping, count)
        self.count = count
        # Each particle's springs, for the force's gather: those it is the first end of, and
        # those it is the second end of (pulled by +f and −f), as CSR lists.
        self._as_first = spring_incidence(self.pairs[:, 0], count)
        self._as_second = spring_incidence(self.pairs[:, 1], count)
        # 32-bit ends: the force pass gathers by them, and AVX-512 gathers 8 at a time with
        # 32-bit indices.
        self._first = np.ascontiguousarray(self.pairs[:, 0], dtype=np.int32)
        self._second = np.ascontiguousarray(self.pairs[:, 1], dtype=np.int32)
        self._touched = np.flatnonzero(
            np.diff(self._as_first[0]) + np.diff(self._as_second[0])
        ).astype(np.int64)
        # The springs as a stencil, if they are a lattice's (see :mod:`.lattice_springs`),
        # and its force on each of the lattice's points.
        self.stencil = (
            None
            if lattice is None
            else SpringStencil.of(
                self.pairs, self.rest_length, self.stiffness, self.damping, *lattice
            )
        )
        # An undamped set of springs is conservative (instances may differ from the class).
        self.conservative = not np.any(self.damping)  # type: ignore[misc]
        self.velocity_dependent = bool(np.any(self.damping))  # type: ignore[misc]

    def __len__(self) -> int:
        return int(self.pairs.shape[0])

    @property
    def compiled(self) -> SpringSet:
        """Its compiled form (the fused particle step sums the springs from it)."""
        return SpringSet(self.pairs, self.rest_length, self.stiffness, self.damping, self.stencil)

    def accumulate(
        self, t: float, x: np.ndarray, v: np.ndarray, out: np.ndarray, work: Workspace | None = None
    ) -> None:
        """Add every spring's force [N] on its two particles to ``out``: each spring's force
        in one parallel pass, then each particle's sum in another (no two threads write the
        same particle, and the sums run in a fixed order: the result does not depend on the
        thread count); or, on a lattice, each point's sum by the stencil."""
        scratch = self._scratch() if work is None else work.get(self, self._scratch)
        columns = scratch.columns
        _columns(x, v, columns)
        if self.stencil is not None:
            self.stencil.forces(columns[:3], columns[3:], scratch.forces)
            _add_rows(scratch.forces, self.stencil.start, out)
            return
        fx, fy, fz = scratch.forces
        spring_forces(
            self._first, self._second, self.rest_length, self.stiffness, self.damping,
            *columns, fx, fy, fz,
        )  # fmt: skip
        _gather(self._touched, *self._as_first, *self._as_second, fx, fy, fz, out)

    def _scratch(self) -> _Scratch:
        points = None if self.stencil is None else self.stencil.points
        return _Scratch(self.count, len(self) if points is None else points)

    def potential(self, t: float, x: np.ndarray, alive: np.ndarray | None = None) -> float:
        """``Σ ½ k (l − L)²`` [J] over the springs."""
        return float(_energy(self.pairs, self.rest_length, self.stiffness, x))

    def jacobian_blocks(self) -> tuple[np.ndarray, np.ndarray]:
        """Per spring, the blocks ``(i, i), (i, j), (j, i), (j, j)``."""
        i, j = self.pairs[:, 0], self.pairs[:, 1]
        rows = np.stack([i, i, j, j], axis=1).reshape(-1)
        cols = np.stack([i, j, i, j], axis=1).reshape(-1)
        return rows, cols

    def add_jacobian(
        self,
        t: float,
        x: np.ndarray,
        v: np.ndarray,
        dfdx: np.ndarray,
        dfdv: np.ndarray,
        form: JacobianForm = "exact",
    ) -> None:
        """Add ``∂F/∂x`` [N/m] and ``∂F/∂v`` [N·s/m] into the blocks of
        :meth:`jacobian_blocks` (``(4S, 3, 3)`` each). ``"symmetric"``: without the damper's
        non-symmetric part (the change of its direction with the positions), so ``∂F/∂x`` is
        ``−∇²U``; ``"definite"``: each spring's stiffness made positive semi-definite too, a
        compressed spring's negative stiffness across it dropped (Choi & Ko 2002)."""
        _jacobian(
            self.pairs,
            self.rest_length,
            self.stiffness,
            self.damping,
            x,
            v,
            form != "exact",
            form == "definite",
            dfdx,
            dfdv,
        )


class _Scratch:
    """A run's arrays for :meth:`Springs.accumulate`: every particle's ``x, y, z, vx, vy, vz``
    ``(6, N)``, and the forces ``(3, n)`` of each spring on its first particle (or of the
    stencil on each lattice point), one array per component (the compiler vectorizes the
    force pass only over contiguous components)."""

    __slots__ = ("columns", "forces")

    def __init__(self, count: int, rows: int) -> None:
        self.columns = np.empty((6, count))
        self.forces = np.empty((3, rows))


def spring_incidence(ends: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """CSR lists of the springs at each particle: the springs with particle ``p`` at ``ends``
    are ``springs[start[p]:start[p + 1]]`` (32-bit, in spring order)."""
    start = np.zeros(count + 1, dtype=np.int64)
    np.cumsum(np.bincount(ends, minlength=count), out=start[1:])
    return start, np.argsort(ends, kind="stable").astype(np.int32)


def _per_spring(name: str, values: object, springs: int) -> np.ndarray:
    """``values`` as ``(S,)`` float64: one per spring, or one for all."""
    array = np.asarray(values, dtype=np.float64)
    if array.ndim == 0:
        return np.full(springs, float(array))
    if array.shape != (springs,):
        raise ModelError(
            f"`{name}` must be one number or one per spring ({springs}), got shape {array.shape}"
        )
    return np.ascontiguousarray(array)


def _check(
    pairs: np.ndarray, rest: np.ndarray, stiffness: np.ndarray, damping: np.ndarray, count: int
) -> None:
    """Refuse the first bad spring, naming it, what is wrong and the fix."""
    checks = [
        (((pairs < 0) | (pairs >= count)).any(axis=1), "joins a particle that does not exist",
         f"indices must be in [0, {count})"),
        (pairs[:, 0] == pairs[:, 1], "joins a particle to itself",
         "a spring needs two different particles"),
        (~(np.isfinite(rest) & (rest > 0.0)), "has a rest length that is not positive and finite",
         "use the distance the spring should keep, > 0 [m]"),
        (~(np.isfinite(stiffness) & (stiffness >= 0.0)), "has a negative or non-finite stiffness",
         "use k >= 0 [N/m]"),
        (~(np.isfinite(damping) & (damping >= 0.0)), "has a negative or non-finite damping",
         "use c >= 0 [N s/m]"),
    ]  # fmt: skip
    for bad, what, fix in checks:
        if bad.any():
            s = int(np.argmax(bad))
            raise ModelError(
                f"spring {s} {what} (particles {pairs[s].tolist()}, rest length {rest[s]!r} m, "
                f"stiffness {stiffness[s]!r} N/m, damping {damping[s]!r} N s/m): {fix}"
            )


@njit(cache=True, error_model="numpy", inline="always")
def _spring(p, x, v, s):  # pragma: no cover - compiled
    """Spring ``s``'s ends, unit direction ``u``, length ``l`` and stretch rate ``w · u``."""
    i, j = p[s, 0], p[s, 1]
    dx, dy, dz = x[j, 0] - x[i, 0], x[j, 1] - x[i, 1], x[j, 2] - x[i, 2]
    length = np.sqrt(dx * dx + dy * dy + dz * dz)
    ux, uy, uz = dx / length, dy / length, dz / length
    wx, wy, wz = v[j, 0] - v[i, 0], v[j, 1] - v[i, 1], v[j, 2] - v[i, 2]
    return i, j, ux, uy, uz, length, wx, wy, wz, wx * ux + wy * uy + wz * uz


@njit(cache=True, parallel=True)
def _columns(x, v, columns):  # pragma: no cover - compiled
    """``columns`` ← the components of ``x`` and ``v`` ``(N, 3)``, one row each."""
    for i in prange(x.shape[0]):
        for a in range(3):
            columns[a, i] = x[i, a]
            columns[3 + a, i] = v[i, a]


# fmt: off
@njit(cache=True, parallel=True, error_model="numpy")
def spring_forces(
    first, second, rest, k, c, x, y, z, vx, vy, vz, fx, fy, fz,
):  # pragma: no cover - compiled
    """``(fx, fy, fz)[s]``: the force of spring ``s`` on its first particle [N] (positions and
    velocities one array per component: gathers from them vectorize)."""
    # fmt: on
    for s in prange(first.shape[0]):
        i, j = first[s], second[s]
        dx, dy, dz = x[j] - x[i], y[j] - y[i], z[j] - z[i]
        length = np.sqrt(dx * dx + dy * dy + dz * dz)
        inverse = 1.0 / length  # one division
        ux, uy, uz = dx * inverse, dy * inverse, dz * inverse
        rate = (vx[j] - vx[i]) * ux + (vy[j] - vy[i]) * uy + (vz[j] - vz[i]) * uz
        magnitude = k[s] * (length - rest[s]) + c[s] * rate
        fx[s] = magnitude * ux
        fy[s] = magnitude * uy
        fz[s] = magnitude * uz


@njit(cache=True, parallel=True)
def _add_rows(columns, start, out):  # pragma: no cover - compiled
    """``out[start + p] += columns[:, p]`` (``out`` ``(N, 3)``, ``columns`` ``(3, n)``)."""
    for p in prange(columns.shape[1]):
        for a in range(3):
            out[start + p, a] += columns[a, p]


@njit(cache=True, parallel=True)
def _gather(
    touched, first_start, as_first, second_start, as_second, fx, fy, fz, out
):  # pragma: no cover - compiled
    """``out[p] += Σ f[s]`` over the springs whose first end is ``p``, ``− Σ f[s]`` over
    those whose second end it is, for each particle ``p`` in ``touched``."""
    for a in prange(touched.shape[0]):
        p = touched[a]
        sx = sy = sz = 0.0
        for b in range(first_start[p], first_start[p + 1]):
            s = as_first[b]
            sx, sy, sz = sx + fx[s], sy + fy[s], sz + fz[s]
        for b in range(second_start[p], second_start[p + 1]):
            s = as_second[b]
            sx, sy, sz = sx - fx[s], sy - fy[s], sz - fz[s]
        out[p, 0] += sx
        out[p, 1] += sy
        out[p, 2] += sz


@njit(cache=True, error_model="numpy")
def _energy(p, rest, k, x):  # pragma: no cover - compiled
    total = 0.0
    for s in range(p.shape[0]):
        i, j = p[s, 0], p[s, 1]
        dx, dy, dz = x[j, 0] - x[i, 0], x[j, 1] - x[i, 1], x[j, 2] - x[i, 2]
        stretch = np.sqrt(dx * dx + dy * dy + dz * dz) - rest[s]
        total += 0.5 * k[s] * stretch * stretch
    return total


@njit(cache=True, parallel=True, error_model="numpy")
def _jacobian(p, rest, k, c, x, v, symmetric, definite, dfdx, dfdv):  # pragma: no cover
    for s in prange(p.shape[0]):
        _, _, ux, uy, uz, length, wx, wy, wz, rate = _spring(p, x, v, s)
        u, w = (ux, uy, uz), (wx, wy, wz)
        across = k[s] * (1.0 - rest[s] / length)  # the stiffness across the spring
        scale = 0.0 if symmetric else c[s] / length
        if definite:
            across = max(across, 0.0)
        for a in range(3):
            for b in range(3):
                along = u[a] * u[b]
                projector = (1.0 if a == b else 0.0) - along
                # (wᵀ P)_b = w_b − (w · u) u_b
                block = (
                    k[s] * along
                    + across * projector
                    + scale * (u[a] * (w[b] - rate * u[b]) + rate * projector)
                )
                damper = c[s] * along
                dfdx[4 * s, a, b] -= block
                dfdx[4 * s + 1, a, b] += block
                dfdx[4 * s + 2, a, b] += block
                dfdx[4 * s + 3, a, b] -= block
                dfdv[4 * s, a, b] -= damper
                dfdv[4 * s + 1, a, b] += damper
                dfdv[4 * s + 2, a, b] += damper
                dfdv[4 * s + 3, a, b] -= damper
