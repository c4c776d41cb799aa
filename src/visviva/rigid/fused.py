"""The fused rigid-body step: a scene of free bodies stepped in one compiled pass.

A scene made only of rigid bodies under gravity and damping, stepped by symplectic Euler (the
scenes' default), spends most of a generic step outside the bodies' arithmetic: the force
function's NumPy passes, the integrator's array sums, the projection stage's norms and the
divergence watch each read and write the state once more. Here one parallel pass does per
body what they do:

    P ← P + h (M g − γ P),    L ← L + h (−γ' L)          the kick (forces and torques)
    x ← x + h P/M,  q ← the free rotation by L            the drift (:mod:`.motion`)

then the watch's check (a body whose numbers leave the watch's bounds is counted, and the
watch looks closer). The drift leaves each quaternion unit, so the projection stage has
nothing to do.

The pass works on its own copy of the bodies, one contiguous array per component, updated in
place, as :mod:`visviva.particles.fused` does for particles; the state's arrays are brought
up to date when someone reads them (:meth:`settled`). The turns take the short series of
:func:`~.motion._small_half_angle`; a body turning further in one step keeps its start values
in that pass and is stepped again by the general path (:func:`~.motion.drift_body`).

Speed, measured at 10,000 bodies on one thread: 80 ns a body (the generic pipeline: 110 ns).
A body's five turns are a chain of dependent operations, so a body at a time is bound by
their latency; the same arithmetic over separate component arrays, vectorized eight bodies
an instruction (AVX-512), took 7 ns a body in a standalone kernel, but this loop, writing the
rows of one 2-D array under selection, is not vectorized yet. The results are the generic
pipeline's to round-off (``tests/test_rigid_bodies.py``); pushes, anchors, particles and the
other integrators take the generic pipeline.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit, prange

from ..geometry.quaternion_kernels import multiply, normalized, rotate_back
from ..integrators.symplectic import drift, kick
from .motion import SMALL_LIMIT, _free_turns, _small_half_angle, drift_body
from .projection import BodyProjection

if TYPE_CHECKING:
    from ..ode.state import State

__all__ = ["FusedBodies"]


class FusedBodies:
    """The fused step of a scene of rigid bodies (see :meth:`of`)."""

    def __init__(self, model: Any) -> None:
        bodies = model.bodies
        motion = bodies.motion(0)
        self.count = bodies.count
        self.inverse_mass = motion.inverse_mass
        self.inverse_inertia = motion.inverse_inertia  # (B, 3), for the general path
        self.axes = motion.axes  # (B, 4)
        self.mass = np.zeros(self.count)  # the masses gravity pulls (see BodyLaw)
        self.gravity = np.zeros(3)
        self.linear = np.zeros(self.count)
        self.angular = np.zeros(self.count)
        for force in model.body_forces:
            form = force.compiled
            if form.gravity.any():
                self.gravity += form.gravity
                self.mass = form.mass
            self.linear += form.linear
            self.angular += form.angular
        # The working copy, one row per component: x, y, z, qw, qx, qy, qz, then P and L.
        self._work = np.empty((13, self.count))
        self._columns = (
            np.ascontiguousarray(self.inverse_inertia.T),
            np.ascontiguousarray(self.axes.T),
        )
        self._special = np.empty(self.count, dtype=np.bool_)
        self._current: State | None = None
        self._settled = True

    @classmethod
    def of(cls, model: Any, method: str) -> FusedBodies | None:
        """The fused step of ``model`` for ``method``, or ``None``: the method must be
        symplectic Euler, the scene made of rigid bodies only, under forces with a compiled
        form (gravity and damping: :class:`~visviva.forces.body_forces.BodyLaw`), its only stage
        the projection onto unit quaternions (which the step's exact rotations make moot)."""
        if method != "symplectic_euler" or model.bodies is None:
            return None
        if model.particle_count or model.systems:
            return None
        if any(f.compiled is None for f in model.body_forces):
            return None
        if not all(isinstance(s, BodyProjection) for s in model.stages):
            return None
        return cls(model)

    def step(self, state: State, h: float, t_after: float, limit: float) -> tuple[State, bool]:
        """Advance ``state`` by ``h`` [s] (``state`` is spent); the state at ``t_after`` and
        whether a body may be beyond ``limit`` or not finite."""
        if state is not self._current:
            _columns_of(*state.parts, self._work)
        inverse_inertia, axes = self._columns
        suspects, special = _step(
            self._work, h, self.mass, self.inverse_mass, inverse_inertia, axes, self.gravity,
            self.linear, self.angular, limit, self._special,
        )  # fmt: skip
        if special:
            suspects += _step_special(
                self._work, h, self.mass, self.inverse_mass, self.inverse_inertia, self.axes,
                self.gravity, self.linear, self.angular, limit, np.flatnonzero(self._special),
            )  # fmt: skip
        self._current = state.from_parts(t_after, state.parts)
        self._settled = False
        return self._current, suspects != 0

    def settled(self, state: State) -> State:
        """``state`` with its bodies up to date (copied from the working copy if it is the
        latest state this step returned)."""
        if state is self._current and not self._settled:
            _interleave(self._work, *state.parts)
            self._settled = True
        return state


@njit(cache=True, parallel=True)
def _columns_of(q, v, work):  # pragma: no cover - compiled
    """``work`` (13, B) ← the bodies' x, q from ``q`` and P, L from ``v``."""
    count = work.shape[1]
    for b in prange(count):
        for a in range(3):
            work[a, b] = q[3 * b + a]
            work[7 + a, b] = v[3 * b + a]
            work[10 + a, b] = v[3 * count + 3 * b + a]
        for a in range(4):
            work[3 + a, b] = q[3 * count + 4 * b + a]


@njit(cache=True, parallel=True)
def _interleave(work, q, v):  # pragma: no cover - compiled
    """The inverse of :func:`_columns_of`."""
    count = work.shape[1]
    for b in prange(count):
        for a in range(3):
            q[3 * b + a] = work[a, b]
            v[3 * b + a] = work[7 + a, b]
            v[3 * count + 3 * b + a] = work[10 + a, b]
        for a in range(4):
            q[3 * count + 4 * b + a] = work[3 + a, b]


#: Bodies a thread steps at a time, by a serial loop (see :func:`_steps`).
_CHUNK = 1024


@njit(cache=True, error_model="numpy")
def _steps(
    work, h, mass, inverse_mass, inverse_inertia, axes, g, linear, angular, limit, special,
    first, last,
):  # pragma: no cover - compiled  # fmt: skip
    """Bodies ``first`` to ``last`` of :func:`_step`, one after the other. A serial loop of its
    own: inlined into a parallel loop's body, the turns computed wrong numbers (Numba 0.68.1's
    parallel lowering; the serial loop is right)."""
    cx, cy, cz, qw, qx, qy, qz = work[0], work[1], work[2], work[3], work[4], work[5], work[6]
    mx, my, mz, lx, ly, lz = work[7], work[8], work[9], work[10], work[11], work[12]
    j1, j2, j3 = inverse_inertia[0], inverse_inertia[1], inverse_inertia[2]
    gx, gy, gz = g[0], g[1], g[2]
    suspects = 0
    odd = 0
    for b in range(first, last):
        # The kick by F = M g − γ P and τ = −γ' L, the forces' compiled forms (BodyLaw).
        m, gamma, spin = mass[b], linear[b], angular[b]
        ux = kick(mx[b], m * gx - gamma * mx[b], h)
        uy = kick(my[b], m * gy - gamma * my[b], h)
        uz = kick(mz[b], m * gz - gamma * mz[b], h)
        kx, ky, kz = (
            kick(lx[b], -spin * lx[b], h),
            kick(ly[b], -spin * ly[b], h),
            kick(lz[b], -spin * lz[b], h),
        )
        r0, r1, r2, r3 = axes[0, b], axes[1, b], axes[2, b], axes[3, b]
        w, x, y, z = normalized(qw[b], qx[b], qy[b], qz[b])
        w, x, y, z = multiply(w, x, y, z, r0, r1, r2, r3)
        px, py, pz = rotate_back(w, x, y, z, kx, ky, kz)
        fastest = max(j1[b], j2[b], j3[b]) * np.sqrt(px * px + py * py + pz * pz)
        # (An isotropic body's one exact turn is the general path's.)
        fits = (0.5 * h * fastest <= SMALL_LIMIT) & ((j1[b] != j2[b]) | (j2[b] != j3[b]))
        turned = _free_turns(w, x, y, z, px, py, pz, h, j1[b], j2[b], j3[b], _small_half_angle)
        w, x, y, z, px, py, pz = turned
        w, x, y, z = multiply(w, x, y, z, r0, -r1, -r2, -r3)
        w, x, y, z = normalized(w, x, y, z)
        im = inverse_mass[b]
        nx, ny, nz = drift(cx[b], ux * im, h), drift(cy[b], uy * im, h), drift(cz[b], uz * im, h)
        # A body that turned too far for the series keeps its start (by selection: a
        # conditional store would keep the loop scalar).
        cx[b] = nx if fits else cx[b]
        cy[b] = ny if fits else cy[b]
        cz[b] = nz if fits else cz[b]
        qw[b] = w if fits else qw[b]
        qx[b] = x if fits else qx[b]
        qy[b] = y if fits else qy[b]
        qz[b] = z if fits else qz[b]
        mx[b] = ux if fits else mx[b]
        my[b] = uy if fits else my[b]
        mz[b] = uz if fits else mz[b]
        lx[b] = kx if fits else lx[b]
        ly[b] = ky if fits else ly[b]
        lz[b] = kz if fits else lz[b]
        special[b] = not fits
        odd += 0 if fits else 1
        extent = (
            abs(nx)
            + abs(ny)
            + abs(nz)
            + abs(w)
            + abs(x)
            + abs(y)
            + abs(z)
            + abs(ux)
            + abs(uy)
            + abs(uz)
            + abs(kx)
            + abs(ky)
            + abs(kz)
        )
        suspects += 0 if extent <= limit else 1
    return suspects, odd


@njit(cache=True, parallel=True, error_model="numpy")
def _step(
    work, h, mass, inverse_mass, inverse_inertia, axes, g, linear, angular, limit, special,
):  # pragma: no cover - compiled  # fmt: skip
    """The step of the module docstring for every body whose turns fit the short series, in
    place; the others keep their start values and are marked ``special``. Returns how many
    bodies may be beyond ``limit`` or not finite, and how many are special."""
    count = mass.shape[0]
    suspects = 0
    odd = 0
    for chunk in prange((count + _CHUNK - 1) // _CHUNK):
        first = chunk * _CHUNK
        s, o = _steps(
            work, h, mass, inverse_mass, inverse_inertia, axes, g, linear, angular, limit,
            special, first, min(count, first + _CHUNK),
        )  # fmt: skip
        suspects += s
        odd += o
    return suspects, odd


# fmt: off
@njit(cache=True, error_model="numpy")
def _step_special(
    work, h, mass, inverse_mass, inverse_inertia, axes, g, linear, angular, limit, which,
):  # pragma: no cover - compiled
    """The bodies ``which`` stepped from their start values by the general path (the series
    for larger turns, or the library's sin and cos); returns how many may be beyond
    ``limit``."""
    # fmt: on
    suspects = 0
    q, v = np.empty(7), np.empty(6)
    for b in which:
        for a in range(3):
            v[a] = kick(work[7 + a, b], mass[b] * g[a] - linear[b] * work[7 + a, b], h)
            v[3 + a] = kick(work[10 + a, b], -angular[b] * work[10 + a, b], h)
            q[a] = work[a, b]
        for a in range(4):
            q[3 + a] = work[3 + a, b]
        drift_body(
            q, v, h, inverse_mass[b : b + 1], inverse_inertia[b : b + 1], axes[b : b + 1], q,
            0, 1,
        )
        extent = 0.0
        for a in range(7):
            work[a, b] = q[a]
            extent += abs(q[a])
        for a in range(6):
            work[7 + a, b] = v[a]
            extent += abs(v[a])
        suspects += 0 if extent <= limit else 1
    return suspects
