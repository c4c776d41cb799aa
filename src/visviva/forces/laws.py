"""The force laws of particle fields, one small compiled function each.

Each law gives the force [N] on one particle from its own position ``x`` [m], velocity ``v``
[m/s] and mass ``m`` [kg] (and, where it has them, its potential energy [J] and its 3×3
Jacobians). The force classes (:mod:`visviva.forces.fields`) loop over particles calling them,
and so does the fused particle step (:mod:`visviva.particles.fused`): one home per law.

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

import numpy as np
from numba import njit

__all__ = [
    "attractor_force",
    "attractor_jacobian",
    "attractor_potential",
    "quadratic_drag_force",
    "quadratic_drag_jacobian",
    "vortex_air_velocity",
    "vortex_jacobian",
]


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
