"""The force laws of particle fields, one small compiled function each.

Each law gives the force [N] on one particle from its own position ``x`` [m], velocity ``v``
[m/s] and mass ``m`` [kg] (and, where it has them, its potential energy [J] and its 3×3
Jacobians). A field force declares its law and its parameter row (:class:`FieldLaw`, its
compiled form); :func:`field_force` evaluates any law by its code, and both roads call it: the
fields' :func:`field_forces` loop on the generic road, and the fused particle step
(:mod:`visviva.particles.fused`), which folds the laws that are affine in the velocity and free
of the position (:data:`FOLDED`: gravity, linear drag, damping) into one acceleration for the
particles they all act on. One home per law.

The laws, with ``d = x − c`` the offset from a field's centre ``c``:

* uniform gravity: ``F = m g``, ``U = −m g·x``;
* linear drag in moving air (wind): ``F = −k (v − w)`` with ``k`` [N·s/m] and the air's
  velocity ``w`` (``w = 0``: still air, Stokes drag);
* quadratic drag: ``F = −c |v − w| (v − w)`` with ``c`` [kg/m] (``½ ρ C_d A`` for a body of
  drag coefficient ``C_d`` and frontal area ``A`` in air of density ``ρ``);
* mass-proportional damping: ``F = −γ m v`` with rate ``γ`` [1/s] (every particle loses speed
  at the same rate whatever its mass);
* point attractor (repulsor for negative strength), Plummer-softened inverse square:
  ``F = −s m d / ρ³``, ``U = −s m / ρ``, ``ρ² = |d|² + ε²``, with strength ``s`` [m³/s²]
  (``G M`` of the attracting body) and softening ``ε`` [m];
* vortex: the air swirls about an axis through ``c`` with unit direction ``a`` as a vortex
  with a smooth core, ``u(x) = Γ/(2π) (a × d) / (|d⊥|² + r²)`` (``d⊥ = d − (d·a) a``,
  circulation ``Γ`` [m²/s], core radius ``r`` [m]: a line vortex far out, solid-body rotation
  inside), and drags the particle towards it: ``F = k (u(x) − v)``.

References:
    Seed 001 (particle forces); W. T. Reeves, "Particle systems — a technique for modeling a
    class of fuzzy objects", SIGGRAPH 1983; H. C. Plummer, MNRAS 71 (1911) 460 (softening);
    G. K. Batchelor, *An Introduction to Fluid Dynamics*, CUP 1967, §7.1 (line vortices).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

if TYPE_CHECKING:
    from .base import Targets

__all__ = [
    "ATTRACTOR",
    "DAMPING",
    "DRAG",
    "FOLDED",
    "GRAVITY",
    "LAW_PARAMETERS",
    "QUADRATIC_DRAG",
    "VORTEX",
    "FieldLaw",
    "attractor_force",
    "attractor_jacobian",
    "attractor_potential",
    "field_force",
    "field_forces",
    "law_row",
    "quadratic_drag_force",
    "quadratic_drag_jacobian",
    "vortex_air_velocity",
    "vortex_jacobian",
]

#: The codes of the laws (:func:`field_force`), with their parameter rows:
#: ``GRAVITY``: g [m/s²] (3); ``DRAG``: air velocity w [m/s] (3), k [N·s/m];
#: ``DAMPING``: γ [1/s]; ``QUADRATIC_DRAG``: w (3), c [kg/m]; ``ATTRACTOR``: centre [m] (3),
#: s [m³/s²], ε² [m²]; ``VORTEX``: a point of the axis (3), the axis (3), Γ/(2π), r² [m²], k.
GRAVITY, DRAG, DAMPING, QUADRATIC_DRAG, ATTRACTOR, VORTEX = range(6)
#: The laws affine in the velocity and free of the position: on particle ``i`` their sum is
#: ``m_i (g − c_i v) + k w`` with ``c_i = k / m_i + γ``, which the fused step folds.
FOLDED = (GRAVITY, DRAG, DAMPING)
#: The longest parameter row of a law.
LAW_PARAMETERS = 9


@dataclass(frozen=True)
class FieldLaw:
    """A field force's compiled form: its law's code, its parameter row and its targets.

    Attributes:
        law: One of the codes above.
        parameters: The law's row (see the codes), at most :data:`LAW_PARAMETERS` numbers.
        targets: The particles it acts on.
    """

    law: int
    parameters: tuple[float, ...]
    targets: Targets

    def row(self) -> tuple[float, ...]:
        """The parameters padded to :data:`LAW_PARAMETERS` numbers (one type for every law)."""
        return law_row(self.parameters)

    def folded(self) -> tuple[np.ndarray, float, np.ndarray, float] | None:
        """A law of :data:`FOLDED` as its terms of ``m (g − c v) + k w`` with ``c = k/m + γ``:
        ``(g [m/s²], k [N·s/m], k w [N], γ [1/s])``; ``None`` for another law."""
        p = np.asarray(self.parameters, dtype=np.float64)
        zero = np.zeros(3)
        if self.law == GRAVITY:
            return p[:3], 0.0, zero, 0.0
        if self.law == DRAG:
            return zero, float(p[3]), p[3] * p[:3], 0.0
        if self.law == DAMPING:
            return zero, 0.0, zero, float(p[0])
        return None


def law_row(parameters: tuple[float, ...]) -> tuple[float, ...]:
    """A law's parameters padded to :data:`LAW_PARAMETERS` numbers (one type for every law)."""
    return (*(float(p) for p in parameters), *(0.0,) * (LAW_PARAMETERS - len(parameters)))


@njit(cache=True, error_model="numpy", inline="always")
def field_force(law, p, x, y, z, vx, vy, vz, m):  # pragma: no cover - compiled
    """The force [N] of law ``law`` with parameters ``p`` (a :data:`LAW_PARAMETERS`-tuple) on a
    particle of mass ``m`` [kg] at ``(x, y, z)`` [m] moving at ``(vx, vy, vz)`` [m/s]."""
    if law == GRAVITY:
        return m * p[0], m * p[1], m * p[2]
    if law == DRAG:
        k = p[3]
        return -(k * (vx - p[0])), -(k * (vy - p[1])), -(k * (vz - p[2]))
    if law == DAMPING:
        c = p[0] * m  # γ m
        return -(c * vx), -(c * vy), -(c * vz)
    if law == QUADRATIC_DRAG:
        return quadratic_drag_force(vx, vy, vz, p[0], p[1], p[2], p[3])
    if law == ATTRACTOR:
        return attractor_force(x, y, z, p[0], p[1], p[2], p[3], p[4], m)
    ux, uy, uz = vortex_air_velocity(x, y, z, p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7])
    return p[8] * (ux - vx), p[8] * (uy - vy), p[8] * (uz - vz)


@njit(cache=True, error_model="numpy")
def field_forces(law, p, index, x, v, m, out):  # pragma: no cover - compiled
    """Add law ``law``'s force [N] on the particles ``index`` into ``out`` ``(N, 3)``."""
    for i in index:
        fx, fy, fz = field_force(law, p, x[i, 0], x[i, 1], x[i, 2], v[i, 0], v[i, 1], v[i, 2], m[i])
        out[i, 0] += fx
        out[i, 1] += fy
        out[i, 2] += fz


@njit(cache=True, error_model="numpy")
def quadratic_drag_force(vx, vy, vz, wx, wy, wz, c):  # pragma: no cover - compiled
    """``−c |u| u`` with ``u = v − w`` [N]."""
    ux, uy, uz = vx - wx, vy - wy, vz - wz
    scale = -c * math.sqrt(ux * ux + uy * uy + uz * uz)
    return scale * ux, scale * uy, scale * uz


@njit(cache=True, error_model="numpy")
def quadratic_drag_jacobian(vx, vy, vz, wx, wy, wz, c, out):  # pragma: no cover - compiled
    """Add ``∂F/∂v = −c (|u| I + u uᵀ / |u|)`` [kg/s] into ``out`` (3×3); zero at ``u = 0``."""
    u = (vx - wx, vy - wy, vz - wz)
    speed = math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    if speed == 0.0:
        return
    for r in range(3):
        for k in range(3):
            out[r, k] -= c * u[r] * u[k] / speed
        out[r, r] -= c * speed


@njit(cache=True, error_model="numpy")
def attractor_force(x, y, z, cx, cy, cz, strength, eps2, m):  # pragma: no cover - compiled
    """``−s m d / ρ³`` [N] (see the module docstring)."""
    dx, dy, dz = x - cx, y - cy, z - cz
    rho2 = dx * dx + dy * dy + dz * dz + eps2
    scale = -strength * m / (rho2 * math.sqrt(rho2))
    return scale * dx, scale * dy, scale * dz


@njit(cache=True, error_model="numpy")
def attractor_potential(x, y, z, cx, cy, cz, strength, eps2, m):  # pragma: no cover - compiled
    """``−s m / ρ`` [J]."""
    dx, dy, dz = x - cx, y - cy, z - cz
    return -strength * m / math.sqrt(dx * dx + dy * dy + dz * dz + eps2)


@njit(cache=True, error_model="numpy")
def attractor_jacobian(x, y, z, cx, cy, cz, strength, eps2, m, out):  # pragma: no cover
    """Add ``∂F/∂x = −s m (I/ρ³ − 3 d dᵀ/ρ⁵)`` [N/m] into ``out`` (3×3)."""
    d = (x - cx, y - cy, z - cz)
    rho2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + eps2
    inverse3 = 1.0 / (rho2 * math.sqrt(rho2))
    inverse5 = inverse3 / rho2
    sm = strength * m
    for r in range(3):
        for k in range(3):
            out[r, k] += 3.0 * sm * d[r] * d[k] * inverse5
        out[r, r] -= sm * inverse3


@njit(cache=True, error_model="numpy")
def vortex_air_velocity(x, y, z, cx, cy, cz, ax, ay, az, factor, core2):  # pragma: no cover
    """The vortex's air velocity ``u(x)`` [m/s]; ``factor = Γ/(2π)``, ``core2 = r²``."""
    dx, dy, dz = x - cx, y - cy, z - cz
    along = dx * ax + dy * ay + dz * az
    across2 = dx * dx + dy * dy + dz * dz - along * along
    scale = factor / (max(across2, 0.0) + core2)
    return scale * (ay * dz - az * dy), scale * (az * dx - ax * dz), scale * (ax * dy - ay * dx)


@njit(cache=True, error_model="numpy")
def vortex_jacobian(x, y, z, cx, cy, cz, ax, ay, az, factor, core2, k, out):  # pragma: no cover
    """Add ``∂F/∂x = k ∂u/∂x`` [N/m] into ``out`` (3×3), where
    ``∂u/∂x = f ([a]ₓ / D − 2 (a × d) d⊥ᵀ / D²)``, ``D = |d⊥|² + r²``, ``f = Γ/(2π)``.
    (``∂F/∂v = −k I`` is the caller's.)"""
    d = (x - cx, y - cy, z - cz)
    a = (ax, ay, az)
    along = d[0] * ax + d[1] * ay + d[2] * az
    across = (d[0] - along * ax, d[1] - along * ay, d[2] - along * az)
    denominator = across[0] ** 2 + across[1] ** 2 + across[2] ** 2 + core2
    cross = (ay * d[2] - az * d[1], az * d[0] - ax * d[2], ax * d[1] - ay * d[0])
    skew = np.zeros((3, 3))
    skew[0, 1], skew[0, 2] = -a[2], a[1]
    skew[1, 0], skew[1, 2] = a[2], -a[0]
    skew[2, 0], skew[2, 1] = -a[1], a[0]
    first = k * factor / denominator
    second = 2.0 * k * factor / (denominator * denominator)
    for r in range(3):
        for c in range(3):
            out[r, c] += first * skew[r, c] - second * cross[r] * across[c]
