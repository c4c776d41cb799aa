"""How rigid bodies move: ``x' = P/M``, ``q' = ½ ω ⊗ q``, and the drift of a symplectic step.

A body's state is ``(x, q, P, L)`` (Baraff & Witkin's notes, §2): the centre of mass ``x`` [m],
the orientation ``q`` (a unit quaternion, body to world), the momentum ``P = M v`` [kg·m/s] and
the angular momentum ``L`` [kg·m²/s], both in the world frame. Forces and torques change the
momenta, ``P' = F``, ``L' = τ``; the momenta move the body,

    x' = P / M,    q' = ½ (0, ω) ⊗ q,    ω = R I_body⁻¹ Rᵀ L          [rad/s]

with ``I_body`` the inertia about the centre of mass in the body's own axes (those its shape
was given in). The kernels work in the principal frame, turned from the body's axes by a fixed
rotation ``r`` (``p_body = R(r) p_principal``, so the principal frame's orientation is
``q ⊗ r``), where ``I_body`` is diagonal (``I₁, I₂, I₃``). ``ω`` is not conserved by a free
body — ``I(t) = R I_body Rᵀ`` turns with it — but ``L`` is: that is why ``L``, not ``ω``, is
the state.

In a scene's integrated arrays the bodies follow the particles and generalized coordinates:
``q = [..., x (3B), q (4B)]`` and ``v = [..., P (3B), L (3B)]``, ``q`` 7 numbers a body and
``v`` 6. :class:`BodyMotion` is the system's :class:`~visviva.ode.system.Kinematics`:

* :meth:`~BodyMotion.rate` gives ``q'`` for the Runge–Kutta methods (explicit Euler, RK4, ...),
  whose linear updates move quaternions off the unit sphere; the projection stage renormalizes
  them after each step, as the lecture's explicit Euler does;
* :meth:`~BodyMotion.drift` moves the bodies for the symplectic methods with ``P`` and ``L``
  held: ``x += h P/M``, and the free rotation by the splitting of Dullweber, Leimkuhler and
  McLachlan (1997): the kinetic energy ``T = Σ Π_k²/2I_k`` of the body-frame angular momentum
  ``Π = Rᵀ L`` is split into its three terms, each of which is a rotation about one principal
  axis by ``h Π_k/I_k``, integrated exactly and composed symmetrically, ``T₁(h/2) T₂(h/2)
  T₃(h) T₂(h/2) T₁(h/2)``. Each sub-step is a rotation of the quaternion (it stays unit to
  round-off) and keeps ``L`` exactly; the composition is symplectic and time-reversible, so a
  free tumbling body's kinetic energy oscillates near its start without drift (the gyroscopic
  term ``ω × Iω`` is inside the exact rotations, not an explicit force that pumps energy in).

References:
    D. Baraff, A. Witkin, "Physically based modeling: rigid body dynamics", SIGGRAPH course
    notes, 2001; A. Dullweber, B. Leimkuhler, R. McLachlan, "Symplectic splitting methods for
    rigid body molecular dynamics", J. Chem. Phys. 107 (1997) 5840; E. Hairer, C. Lubich,
    G. Wanner, *Geometric Numerical Integration*, 2nd ed., Springer 2006, §VII.5.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..geometry.quaternion_kernels import multiply, normalized, rotate, rotate_back
from ..integrators.symplectic import drift

__all__ = ["BodyMotion"]


class BodyMotion:
    """The kinematics of ``B`` rigid bodies after ``offset`` entries that move as ``q' = v``.

    Args:
        offset: Entries of ``q`` and ``v`` before the bodies (particles' coordinates, the
            named systems'): they move as ``q' = v``.
        mass: ``(B,)`` masses [kg] (``inf`` for a body nothing moves).
        inertia: ``(B, 3)`` principal moments ``I₁, I₂, I₃`` [kg·m²] about the centre of mass
            (``inf`` for a body nothing turns).
        axes: ``(B, 4)`` unit quaternions ``r``: each body's principal frame in its own axes
            (default: the identity, the body's axes are principal).
    """

    def __init__(
        self,
        offset: int,
        mass: np.ndarray,
        inertia: np.ndarray,
        axes: np.ndarray | None = None,
    ) -> None:
        self.offset = offset
        self.count = int(np.shape(mass)[0])
        with np.errstate(divide="ignore"):
            self.inverse_mass = 1.0 / np.asarray(mass, dtype=np.float64)
            self.inverse_inertia = 1.0 / np.asarray(inertia, dtype=np.float64).reshape(-1, 3)
        identity = np.tile([1.0, 0.0, 0.0, 0.0], (self.count, 1))
        self.axes = identity if axes is None else np.asarray(axes, dtype=np.float64)

    def rate(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``q'``: ``v`` for the entries before the bodies, then ``P/M`` and ``½ (0, ω) ⊗ q``."""
        out = np.empty_like(q)
        n = self.offset
        out[:n] = v[:n]
        _rates(q[n:], v[n:], self.inverse_mass, self.inverse_inertia, self.axes, out[n:])
        return out

    def drift(self, q: np.ndarray, v: np.ndarray, h: float) -> np.ndarray:
        """The positions after ``h`` [s] with ``v`` (and the momenta) held: ``q + h v`` before
        the bodies, the bodies' translation and free rotation (see the module docstring)."""
        out = np.empty_like(q)
        n = self.offset
        out[:n] = drift(q[:n], v[:n], h)
        run = _drift_parallel if self.count >= PARALLEL_MIN_BODIES else _drift_serial
        run(q[n:], v[n:], h, self.inverse_mass, self.inverse_inertia, self.axes, out[n:])
        return out

    def kinetic_energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """``Σ |P|²/2M + ½ Πᵀ I_body⁻¹ Π`` [J] over the bodies."""
        n = self.offset
        return float(
            _kinetic_energy(q[n:], v[n:], self.inverse_mass, self.inverse_inertia, self.axes)
        )

    def angular_velocity(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``ω = R I_body⁻¹ Rᵀ L`` [rad/s] of every body, ``(B, 3)`` in the world frame."""
        out = np.empty((self.count, 3))
        n = self.offset
        _angular_velocities(q[n:], v[n:], self.inverse_inertia, self.axes, out)
        return out


@njit(cache=True, inline="always")
def _principal(q, b, count, axes):  # pragma: no cover - compiled
    """Body ``b``'s principal frame's orientation ``q ⊗ r``, unit, from the bodies' part of
    ``q`` (``count`` bodies)."""
    k = 3 * count + 4 * b
    w, x, y, z = normalized(q[k], q[k + 1], q[k + 2], q[k + 3])
    return multiply(w, x, y, z, axes[b, 0], axes[b, 1], axes[b, 2], axes[b, 3])


@njit(cache=True, inline="always")
def _omega(w, x, y, z, lx, ly, lz, inverse_inertia, b):  # pragma: no cover - compiled
    """``ω = R I⁻¹ Rᵀ L`` in the world frame, and ``Π = Rᵀ L`` in the body frame."""
    px, py, pz = rotate_back(w, x, y, z, lx, ly, lz)
    ox, oy, oz = rotate(
        w, x, y, z,
        px * inverse_inertia[b, 0], py * inverse_inertia[b, 1], pz * inverse_inertia[b, 2],
    )  # fmt: skip
    return ox, oy, oz


@njit(cache=True, parallel=True)
def _rates(q, v, inverse_mass, inverse_inertia, axes, out):  # pragma: no cover - compiled
    count = inverse_mass.shape[0]
    for b in prange(count):
        for a in range(3):
            out[3 * b + a] = v[3 * b + a] * inverse_mass[b]
        k, m = 3 * count + 4 * b, 3 * count + 3 * b
        w, x, y, z = _principal(q, b, count, axes)
        ox, oy, oz = _omega(w, x, y, z, v[m], v[m + 1], v[m + 2], inverse_inertia, b)
        # ½ (0, ω) ⊗ q on the quaternion as stored (its linear growth is the projection's).
        dw, dx, dy, dz = multiply(0.0, ox, oy, oz, q[k], q[k + 1], q[k + 2], q[k + 3])
        out[k], out[k + 1], out[k + 2], out[k + 3] = 0.5 * dw, 0.5 * dx, 0.5 * dy, 0.5 * dz


#: Bodies from which the per-body passes run on every thread (below, one thread is faster).
PARALLEL_MIN_BODIES = 2048

#: Largest ``|½θ|`` the series of :func:`_half_angle` takes: its first omitted terms,
#: ``0.4¹⁶/16!`` and ``0.4¹⁷/17!``, are below 1e-19. A body that may turn further in one step
#: (``½ h |L| / I_min`` above it: no sub-turn's half angle can be larger, since ``|Π| = |L|``)
#: takes the library's ``sin`` and ``cos``.
SERIES_LIMIT = 0.4


@njit(cache=True, inline="always")
def _half_angle(angle):  # pragma: no cover - compiled
    """``(cos ½θ, sin ½θ)`` by Taylor series to round-off for ``|½θ| ≤`` :data:`SERIES_LIMIT`
    (no call: a step's five turns would otherwise spend most of their time in the library)."""
    x = 0.5 * angle
    u = x * x
    # Horner, nested from the highest terms: cos to x¹⁴/14!, sin to x¹⁵/15!, multiplying by
    # the reciprocals of k (k − 1) (divisions would take most of the step's time).
    c = 1.0 - u * 0.005494505494505495
    c = 1.0 - u * 0.007575757575757576 * c
    c = 1.0 - u * 0.011111111111111112 * c
    c = 1.0 - u * 0.017857142857142856 * c
    c = 1.0 - u * 0.03333333333333333 * c
    c = 1.0 - u * 0.08333333333333333 * c
    c = 1.0 - u * 0.5 * c
    s = 1.0 - u * 0.004761904761904762
    s = 1.0 - u * 0.00641025641025641 * s
    s = 1.0 - u * 0.00909090909090909 * s
    s = 1.0 - u * 0.013888888888888888 * s
    s = 1.0 - u * 0.023809523809523808 * s
    s = 1.0 - u * 0.05 * s
    s = 1.0 - u * 0.16666666666666666 * s
    return c, x * s


#: Largest ``|½θ|`` the short series of :func:`_small_half_angle` takes (to x⁸/8! and x⁹/9!:
#: the first omitted term, ``0.05¹⁰/10!``, is 3e-20): the turns of an ordinary step.
SMALL_LIMIT = 0.05


@njit(cache=True, inline="always")
def _small_half_angle(angle):  # pragma: no cover - compiled
    """``(cos ½θ, sin ½θ)`` for ``|½θ| ≤`` :data:`SMALL_LIMIT`, evaluated in Estrin's form
    (the powers of ``x²`` side by side, not one after the other as Horner's rule has them):
    a step's five turns follow one another, so their latency is the step's time."""
    x = 0.5 * angle
    u = x * x
    v = u * u
    c = (1.0 - 0.5 * u) + v * ((1.0 / 24.0 - u * (1.0 / 720.0)) + v * (1.0 / 40320.0))
    s = (1.0 - u * (1.0 / 6.0)) + v * ((1.0 / 120.0 - u * (1.0 / 5040.0)) + v * (1.0 / 362880.0))
    return c, x * s


@njit(cache=True, inline="always")
def _library_half_angle(angle):  # pragma: no cover - compiled
    """``(cos ½θ, sin ½θ)`` by the library (for a body turning fast, see
    :data:`SERIES_LIMIT`)."""
    return np.cos(0.5 * angle), np.sin(0.5 * angle)


@njit(cache=True, inline="always")
def _turn(w, x, y, z, px, py, pz, axis, angle, half_angle):  # pragma: no cover - compiled
    """One exact sub-flow of the splitting: the body turns by ``θ = angle`` about its
    principal ``axis`` (0, 1, 2; a constant at each call, so the branches fold away):
    ``q ← q ⊗ (cos ½θ, sin ½θ e)``, and ``Π`` turns by ``−θ`` about ``e`` (``L`` stays).
    Written out per axis: the generic product would multiply by the zeros of ``e``.
    ``half_angle``: :func:`_half_angle` or :func:`_library_half_angle` (a compiled function,
    resolved when compiling)."""
    c, s = half_angle(angle)
    cos, sin = c * c - s * s, 2.0 * s * c  # of θ itself
    if axis == 0:
        q = (w * c - x * s, x * c + w * s, y * c + z * s, z * c - y * s)
        return (*q, px, py * cos + pz * sin, pz * cos - py * sin)
    if axis == 1:
        q = (w * c - y * s, x * c - z * s, y * c + w * s, z * c + x * s)
        return (*q, px * cos - pz * sin, py, pz * cos + px * sin)
    q = (w * c - z * s, x * c + y * s, y * c - x * s, z * c + w * s)
    return (*q, px * cos + py * sin, py * cos - px * sin, pz)


@njit(cache=True, inline="always")
def _free_turns(w, x, y, z, px, py, pz, h, i1, i2, i3, half_angle):  # pragma: no cover
    """The free rotation over ``h``: T₁(h/2) T₂(h/2) T₃(h) T₂(h/2) T₁(h/2), each angle from
    the Π of its moment (``i1, i2, i3`` the inverse principal moments)."""
    w, x, y, z, px, py, pz = _turn(w, x, y, z, px, py, pz, 0, 0.5 * h * px * i1, half_angle)
    w, x, y, z, px, py, pz = _turn(w, x, y, z, px, py, pz, 1, 0.5 * h * py * i2, half_angle)
    w, x, y, z, px, py, pz = _turn(w, x, y, z, px, py, pz, 2, h * pz * i3, half_angle)
    w, x, y, z, px, py, pz = _turn(w, x, y, z, px, py, pz, 1, 0.5 * h * py * i2, half_angle)
    return _turn(w, x, y, z, px, py, pz, 0, 0.5 * h * px * i1, half_angle)


@njit(cache=True, inline="always", error_model="numpy")
def drift_body(q, v, h, inverse_mass, inverse_inertia, axes, out, b, count):  # pragma: no cover
    """Body ``b``'s drift into ``out`` (see the module docstring; ``out`` may be ``q``)."""
    m, k = 3 * count + 3 * b, 3 * count + 4 * b
    for a in range(3):
        out[3 * b + a] = drift(q[3 * b + a], v[3 * b + a] * inverse_mass[b], h)
    w, x, y, z = _principal(q, b, count, axes)
    px, py, pz = rotate_back(w, x, y, z, v[m], v[m + 1], v[m + 2])
    i1, i2, i3 = inverse_inertia[b, 0], inverse_inertia[b, 1], inverse_inertia[b, 2]
    fastest = max(i1, i2, i3) * np.sqrt(px * px + py * py + pz * pz)  # |L| / I_min [rad/s]
    largest = 0.5 * h * fastest  # no sub-turn's |½θ| can be larger
    if i1 == i2 == i3:
        # An isotropic body (and every kinematic one) turns about L at ω = L/I: one exact
        # turn, where the splitting's three would leave an O(h³) error a step.
        norm = np.sqrt(px * px + py * py + pz * pz)
        c, s = _library_half_angle(h * i1 * norm)
        e = s / norm if norm > 0.0 else 0.0
        w, x, y, z = multiply(w, x, y, z, c, e * px, e * py, e * pz)
    elif largest <= SMALL_LIMIT:
        w, x, y, z, px, py, pz = _free_turns(
            w, x, y, z, px, py, pz, h, i1, i2, i3, _small_half_angle
        )
    elif largest <= SERIES_LIMIT:
        w, x, y, z, px, py, pz = _free_turns(w, x, y, z, px, py, pz, h, i1, i2, i3, _half_angle)
    else:
        w, x, y, z, px, py, pz = _free_turns(
            w, x, y, z, px, py, pz, h, i1, i2, i3, _library_half_angle
        )
    # Back to the body's own axes: q = (q ⊗ r) ⊗ r⁻¹.
    w, x, y, z = multiply(w, x, y, z, axes[b, 0], -axes[b, 1], -axes[b, 2], -axes[b, 3])
    out[k], out[k + 1], out[k + 2], out[k + 3] = normalized(w, x, y, z)


# A serial and a parallel driver, separate functions so that each has its own entry in
# Numba's cache: on two threads the parallel one costs about 0.1 ms more a call (measured,
# 200 bodies), more than a few hundred bodies' drift.
@njit(cache=True, error_model="numpy")
def _drift_serial(q, v, h, inverse_mass, inverse_inertia, axes, out):  # pragma: no cover
    count = inverse_mass.shape[0]
    for b in range(count):
        drift_body(q, v, h, inverse_mass, inverse_inertia, axes, out, b, count)


@njit(cache=True, parallel=True, error_model="numpy")
def _drift_parallel(q, v, h, inverse_mass, inverse_inertia, axes, out):  # pragma: no cover
    count = inverse_mass.shape[0]
    for b in prange(count):
        drift_body(q, v, h, inverse_mass, inverse_inertia, axes, out, b, count)


@njit(cache=True)
def _kinetic_energy(q, v, inverse_mass, inverse_inertia, axes):  # pragma: no cover
    count = inverse_mass.shape[0]
    total = 0.0
    for b in range(count):
        p2 = v[3 * b] ** 2 + v[3 * b + 1] ** 2 + v[3 * b + 2] ** 2
        total += 0.5 * p2 * inverse_mass[b]
        w, x, y, z = _principal(q, b, count, axes)
        m = 3 * count + 3 * b
        px, py, pz = rotate_back(w, x, y, z, v[m], v[m + 1], v[m + 2])
        i = inverse_inertia[b]
        total += 0.5 * (px * px * i[0] + py * py * i[1] + pz * pz * i[2])
    return total


@njit(cache=True, parallel=True)
def _angular_velocities(q, v, inverse_inertia, axes, out):  # pragma: no cover - compiled
    count = out.shape[0]
    for b in prange(count):
        w, x, y, z = _principal(q, b, count, axes)
        m = 3 * count + 3 * b
        out[b, 0], out[b, 1], out[b, 2] = _omega(
            w, x, y, z, v[m], v[m + 1], v[m + 2], inverse_inertia, b
        )
