"""Newtonian gravitation between point masses: accelerations and potential energy.

Every body pulls every other (seed 004): with Plummer softening ``ε`` (Plummer 1911; Aarseth,
*Gravitational N-Body Simulations*, Cambridge 2003, §2.2),

    a_i = G Σ_{j≠i} m_j (x_j − x_i) / (|x_j − x_i|² + ε²)^{3/2}            [m/s²]
    U   = −G Σ_{i<j} m_i m_j / (|x_j − x_i|² + ε²)^{1/2}                  [J]

``ε = 0`` is Newton's law; ``ε > 0`` caps the force of a close encounter, which is what a
simulation of many bodies with a fixed step needs (without it two bodies passing close enough
gain an arbitrary kick), and stands in for bodies that are clouds rather than points. SI units
throughout: ``G`` defaults to CODATA 2018; pass ``G=1`` for N-body units.

Two methods: ``"direct"`` sums all ``N(N − 1)`` pairs exactly (Numba, every core); and
``"barnes_hut"`` (:mod:`visviva.mechanics.barnes_hut`) approximates far groups of bodies by
their multipoles in ``O(N log N)``, with a relative error set by the opening angle ``theta``.

Conservation by construction (direct method): the kernel forms each pair's force as
``F_ij = (m_i m_j) (x_j − x_i) / r³``. Floating-point subtraction is antisymmetric
(``x_i − x_j`` is exactly ``−(x_j − x_i)``), squares and the product ``m_i m_j`` are symmetric,
so ``F_ji = −F_ij`` to the last bit; the only rounding left in ``Σ_i m_i a_i`` is that of
adding the forces up, a few units of ``ε_machine · Σ |F|``. (Computing ``m_j / r³`` first and
multiplying by ``m_i`` afterwards, the textbook order, breaks that symmetry in the last bit.)
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit, prange

from .._registry import did_you_mean
from .._validation import describe, real_number
from ..errors import ModelError

__all__ = [
    "GRAVITATIONAL_CONSTANT",
    "MAX_COORDINATE",
    "METHODS",
    "gravitational_potential_energy",
    "gravity_accelerations",
]

#: Newtonian constant of gravitation G [m³/(kg s²)], CODATA 2018 recommended value.
GRAVITATIONAL_CONSTANT = 6.67430e-11

#: Largest accepted coordinate magnitude [m]. Far beyond any physical system (the observable
#: universe is ~4e26 m), and small enough that squared distances and second moments of mass
#: never overflow.
MAX_COORDINATE = 1e100

#: The force methods, for ``method=``.
METHODS = ("direct", "barnes_hut")

# Floating-point licence of the kernels. Allowed: contraction into FMA, reciprocal for
# division, no signed zeros, approximate library functions (sqrt stays IEEE-exact on x86);
# these change results in the last bits only. `reassoc` is given to the sums alone, so that
# the compiler may split each sum over j into SIMD lanes (a different, fixed rounding order);
# the pair weight is compiled without it, because re-association would regroup (m_i m_j) r⁻³
# as m_i (m_j r⁻³) and lose the bit-exact antisymmetry of pair forces. NaN and infinity stay
# honoured (no nnan/ninf): a collapsed or exploding state must show up as non-finite.
_EXACT = {"contract", "arcp", "nsz", "afn"}
_SUMS = _EXACT | {"reassoc"}


@njit(cache=True, fastmath=_EXACT, error_model="numpy")
def _pair_weight(row_mass, mass, r2):  # pragma: no cover - compiled
    """``(m_i m_j) / r³`` for ``r² = r2``; zero for a zero distance (no defined direction)."""
    inverse_cube = 1.0 / (r2 * np.sqrt(r2)) if r2 > 0.0 else 0.0
    return (row_mass * mass) * inverse_cube


@njit(cache=True, fastmath=_SUMS, error_model="numpy")
def body_acceleration(x, y, z, mass, row_mass, eps2, factor, i):  # pragma: no cover - compiled
    """``factor Σ_j F_ij / row_mass[i]`` for body ``i`` and the number of zero-distance pairs.

    ``row_mass`` is ``mass`` except 1 for massless bodies (test particles), whose acceleration
    is then ``factor Σ_j m_j (x_j − x_i) / r³`` as it should be. The self term has a zero
    separation and contributes exactly nothing; with ``eps2 = 0`` it is one of the counted
    zero-distance pairs. The one pair sum of the direct method: every kernel calls it.
    """
    xi, yi, zi, mi = x[i], y[i], z[i], row_mass[i]
    fx = 0.0
    fy = 0.0
    fz = 0.0
    zeros = 0
    for j in range(x.shape[0]):
        dx = x[j] - xi
        dy = y[j] - yi
        dz = z[j] - zi
        r2 = dx * dx + dy * dy + dz * dz + eps2
        zeros += 1 if r2 == 0.0 else 0
        w = _pair_weight(mi, mass[j], r2)
        fx += w * dx
        fy += w * dy
        fz += w * dz
    scale = factor / mi
    return scale * fx, scale * fy, scale * fz, zeros


@njit(cache=True, parallel=True, fastmath=_SUMS, error_model="numpy")
def _direct_accelerations(x, y, z, mass, row_mass, eps2, factor, targets, out):  # pragma: no cover
    """Fill ``out[k]`` with the acceleration of body ``targets[k]``
    (:func:`body_acceleration`); return the number of zero-distance pairs."""
    zero_pairs = 0
    for k in prange(targets.shape[0]):
        ax, ay, az, zeros = body_acceleration(x, y, z, mass, row_mass, eps2, factor, targets[k])
        out[k, 0] = ax
        out[k, 1] = ay
        out[k, 2] = az
        zero_pairs += zeros
    return zero_pairs


@njit(cache=True, fastmath=_SUMS, error_model="numpy")
def row_potential(x, y, z, mass, eps2, i):  # pragma: no cover - compiled
    """``Σ_{j>i} m_i m_j / r_ij`` and the number of zero distances among those pairs."""
    total = 0.0
    zeros = 0
    for j in range(i + 1, x.shape[0]):
        dx = x[j] - x[i]
        dy = y[j] - y[i]
        dz = z[j] - z[i]
        r2 = dx * dx + dy * dy + dz * dz + eps2
        zeros += r2 == 0.0
        # Computed for every pair and then selected (a branch around the division would stop
        # the loop from vectorizing: 2.3× slower).
        inverse = 1.0 / np.sqrt(r2)
        total += mass[j] * (inverse if r2 > 0.0 else 0.0)
    return mass[i] * total, zeros


@njit(cache=True, parallel=True, fastmath=_SUMS, error_model="numpy")
def _direct_potential(x, y, z, mass, eps2):  # pragma: no cover - compiled
    """``Σ_{i<j} m_i m_j / r_ij`` and the number of zero-distance pairs.

    Row ``k`` (``N − k − 1`` pairs) is paired with row ``N − 1 − k`` (``k`` pairs) so that every
    parallel iteration does the same work.
    """
    n = x.shape[0]
    total = 0.0
    zero_pairs = 0
    for k in prange((n + 1) // 2):
        part, zeros = row_potential(x, y, z, mass, eps2, k)
        if n - 1 - k != k:
            other, more = row_potential(x, y, z, mass, eps2, n - 1 - k)
            part += other
            zeros += more
        total += part
        zero_pairs += zeros
    return total, zero_pairs


class PointMasses:
    """Validated point masses in the form the kernels take (structure of arrays).

    Masses are stored divided by a power of two near the largest mass (exact: only the exponent
    changes), so that products ``m_i m_j`` cannot overflow whatever the unit system.

    Attributes:
        count: Number of bodies ``N``.
        x, y, z: Coordinates [m], shape ``(N,)`` each, contiguous.
        mass: Masses divided by ``mass_scale``, shape ``(N,)``.
        row_mass: ``mass``, with 1 in place of 0 (the divisor of each body's force sum).
        mass_scale: The power of two [kg] the masses were divided by.
        eps2: Squared softening length [m²].
    """

    def __init__(self, positions: np.ndarray, masses: np.ndarray, softening: float) -> None:
        self.count = masses.shape[0]
        self.x, self.y, self.z = (np.ascontiguousarray(positions[:, k]) for k in range(3))
        largest = float(masses.max(initial=0.0))
        self.mass_scale = math.ldexp(1.0, math.frexp(largest)[1]) if largest > 0 else 1.0
        self.mass = masses / self.mass_scale
        self.row_mass = np.where(self.mass > 0.0, self.mass, 1.0)
        self.eps2 = softening * softening

    def positions(self) -> np.ndarray:
        """The coordinates as an ``(N, 3)`` array [m]."""
        return np.stack([self.x, self.y, self.z], axis=1)


def check_positions(name: str, positions: Any, count: int | None = None) -> np.ndarray:
    """``positions`` as a float64 ``(N, 3)`` array, finite and within :data:`MAX_COORDINATE`."""
    try:
        array = np.asarray(positions, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ModelError(f"`{name}` must be an (N, 3) array of numbers [m]") from exc
    expected = "(N, 3)" if count is None else f"({count}, 3)"
    if array.ndim != 2 or array.shape[1] != 3 or (count is not None and array.shape[0] != count):
        raise ModelError(f"`{name}` must have shape {expected} (got shape {array.shape})")
    if array.shape[0] == 0:
        raise ModelError(f"`{name}` must hold at least one body (got shape {array.shape})")
    bad = ~(np.abs(array) <= MAX_COORDINATE)
    if bad.any():
        body, axis = (int(k) for k in np.argwhere(bad)[0])
        value = describe(array[body, axis])
        limit = "finite" if not np.isfinite(array[body, axis]) else f"within ±{MAX_COORDINATE:g} m"
        raise ModelError(f"`{name}` of body {body} must be {limit} (got {value} in axis {axis})")
    return array


def check_masses(masses: Any, count: int) -> np.ndarray:
    """``masses`` as a float64 ``(N,)`` array of finite, non-negative values [kg]."""
    try:
        array = np.asarray(masses, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ModelError(f"`masses` must be an array of {count} numbers [kg]") from exc
    if array.shape != (count,):
        raise ModelError(
            f"`masses` must have shape ({count},), one per body (got shape {array.shape})"
        )
    bad = ~(array >= 0.0) | ~np.isfinite(array)
    if bad.any():
        body = int(np.argmax(bad))
        raise ModelError(
            f"`masses` of body {body} must be finite and zero or positive (got "
            f"{describe(array[body])} kg); a massless body is a test particle"
        )
    return array


def check_method(method: Any, theta: Any) -> tuple[str, float]:
    """The method name and the opening angle, checked."""
    if not isinstance(method, str) or method not in METHODS:
        hint = did_you_mean(method, METHODS) if isinstance(method, str) else ""
        raise ModelError(
            f"unknown `method` {method!r}; choose {' or '.join(map(repr, METHODS))}.{hint}"
        )
    angle = real_number("theta", theta, positive=True)
    if angle > 1.0:
        raise ModelError(
            f"`theta` must be in (0, 1] (got {angle!r}): beyond 1 a cell may be used for bodies "
            "inside its own extent, where its multipole expansion does not converge"
        )
    return method, angle


def prepare(
    positions: Any, masses: Any, G: Any, softening: Any, method: Any, theta: Any
) -> tuple[PointMasses, float, str, float]:
    """Check every argument; return the bodies, ``G``, the method and ``theta``."""
    array = check_positions("positions", positions)
    checked = check_masses(masses, array.shape[0])
    gravity = real_number("G", G, positive=True, unit=" m³/(kg s²)")
    epsilon = real_number("softening", softening, nonnegative=True)
    name, angle = check_method(method, theta)
    return PointMasses(array, checked, epsilon), gravity, name, angle


def coincidence_error(bodies: PointMasses) -> ModelError:
    """The error for bodies at zero distance without softening, naming two of them."""
    positions = bodies.positions()
    order = np.lexsort(positions.T[::-1])
    ranked = positions[order]
    same = np.flatnonzero((ranked[1:] == ranked[:-1]).all(axis=1))
    if same.size == 0:
        return ModelError(
            "two bodies are closer than about 1.5e-154 m, where their squared distance "
            "underflows to zero; give `softening` > 0"
        )
    i, j = sorted(int(b) for b in order[same[0] : same[0] + 2])
    return ModelError(
        f"bodies {i} and {j} coincide at {describe(positions[i])} m, where Newton's force has "
        "no direction and no bound; give `softening` > 0 or move them apart"
    )


def direct_accelerations_of(
    targets: np.ndarray, bodies: PointMasses, factor: float, out: np.ndarray
) -> int:
    """Exact accelerations of the bodies ``targets`` (indices) into ``out`` ``(len(targets), 3)``,
    in units of ``factor`` (``G`` times the mass scale); return the number of zero-distance pairs.
    """
    b = bodies
    return int(
        _direct_accelerations(b.x, b.y, b.z, b.mass, b.row_mass, b.eps2, factor, targets, out)
    )


def accelerations_into(
    bodies: PointMasses, G: float, method: str, theta: float, out: np.ndarray
) -> np.ndarray:
    """Fill ``out`` ``(N, 3)`` with the accelerations [m/s²] of already-checked bodies.

    Raises:
        ModelError: If two bodies coincide and there is no softening.
    """
    factor = G * bodies.mass_scale
    if method == "direct":
        zero_pairs = direct_accelerations_of(np.arange(bodies.count), bodies, factor, out)
        # Without softening each body's own term is one zero-distance pair.
        coincident = zero_pairs > (bodies.count if bodies.eps2 == 0.0 else 0)
    else:
        from .barnes_hut import tree_gravity

        coincident = not tree_gravity(bodies, theta, factor, out, None)
    if coincident:
        raise coincidence_error(bodies)
    return out


def potential_energy(bodies: PointMasses, G: float, method: str, theta: float) -> float:
    """``U`` [J] of already-checked bodies (see :func:`gravitational_potential_energy`)."""
    factor = G * bodies.mass_scale * bodies.mass_scale
    if method == "direct":
        total, zero_pairs = _direct_potential(
            bodies.x, bodies.y, bodies.z, bodies.mass, bodies.eps2
        )
        if zero_pairs > 0:
            raise coincidence_error(bodies)
        return -factor * float(total)
    from .barnes_hut import tree_gravity

    scratch = np.empty((bodies.count, 3))
    potential = np.empty(bodies.count)
    if not tree_gravity(bodies, theta, 1.0, scratch, potential):
        raise coincidence_error(bodies)
    # φ_i counts every pair from both ends: U = ½ Σ_i m_i φ_i.
    return 0.5 * factor * float(np.dot(bodies.mass, potential))


def _check_out(out: Any, count: int) -> np.ndarray:
    if not isinstance(out, np.ndarray) or out.dtype != np.float64 or out.shape != (count, 3):
        got = f"{out.dtype} array of shape {out.shape}" if isinstance(out, np.ndarray) else out
        raise ModelError(f"`out` must be a float64 array of shape ({count}, 3) (got {got!r})")
    if not out.flags.writeable:
        raise ModelError("`out` must be writable")
    return out


def gravity_accelerations(
    positions: Any,
    masses: Any,
    *,
    G: float = GRAVITATIONAL_CONSTANT,
    softening: float = 0.0,
    method: str = "direct",
    theta: float = 0.5,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Gravitational acceleration of every body due to all the others.

    Args:
        positions: Body positions [m], shape ``(N, 3)``; finite, within ±:data:`MAX_COORDINATE`.
        masses: Body masses [kg], shape ``(N,)``, zero or positive (a massless body feels the
            others but pulls on nothing: a test particle).
        G: Constant of gravitation [m³/(kg s²)]; ``1`` for N-body units.
        softening: Plummer softening length ``ε`` [m], zero or positive.
        method: ``"direct"`` (exact pair sum, ``O(N²)``) or ``"barnes_hut"`` (octree,
            ``O(N log N)``; error vs direct in :mod:`visviva.mechanics.barnes_hut`).
        theta: Opening angle of ``"barnes_hut"`` in ``(0, 1]``: a cell of radius ``b`` is used
            whole for bodies farther than ``b / theta`` from its centre of mass. Smaller is more
            accurate and slower.
        out: Optional float64 ``(N, 3)`` array to write into (and return).

    Returns:
        Accelerations [m/s²], shape ``(N, 3)``.

    Raises:
        ModelError: For invalid input, including two bodies at one point with ``softening=0``.

    Example:
        >>> import numpy as np, visviva as vv
        >>> earth = 5.9722e24  # kg
        >>> a = vv.mechanics.gravity_accelerations([[0, 0, 0], [6.371e6, 0, 0]], [earth, 1.0])
        >>> round(float(-a[1, 0]), 3)  # g at the Earth's surface [m/s²]
        9.82
    """
    bodies, gravity, name, angle = prepare(positions, masses, G, softening, method, theta)
    target = np.empty((bodies.count, 3)) if out is None else _check_out(out, bodies.count)
    accelerations_into(bodies, gravity, name, angle, target)
    if not np.isfinite(target).all():
        body = int(np.argwhere(~np.isfinite(target))[0, 0])
        raise ModelError(
            f"the acceleration of body {body} overflowed ({describe(target[body])} m/s²): "
            "another body is too close for floating point; give `softening` > 0"
        )
    return target


def gravitational_potential_energy(
    positions: Any,
    masses: Any,
    *,
    G: float = GRAVITATIONAL_CONSTANT,
    softening: float = 0.0,
    method: str = "direct",
    theta: float = 0.5,
) -> float:
    """Total gravitational potential energy ``U = −G Σ_{i<j} m_i m_j / √(r_ij² + ε²)`` [J].

    The acceleration of each body is ``−∇_i U / m_i`` (:func:`gravity_accelerations` with the
    same ``G`` and ``softening``). Arguments as for :func:`gravity_accelerations`; with
    ``"barnes_hut"`` each body's potential comes from the same tree walk as its force, with a
    similar relative error.

    Example:
        >>> import visviva as vv
        >>> vv.mechanics.gravitational_potential_energy([[0, 0, 0], [2, 0, 0]], [3, 4], G=1)
        -6.0
    """
    bodies, gravity, name, angle = prepare(positions, masses, G, softening, method, theta)
    return potential_energy(bodies, gravity, name, angle)
