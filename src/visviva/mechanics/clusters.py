"""Many-body initial conditions: a star cluster in equilibrium, disk galaxies, a collision.

Every function draws from ``numpy.random.default_rng(seed)`` (an ``int`` or a ``Generator``),
never from global state, so a seed gives the same bodies on every machine.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from .._validation import real_number, whole_number
from ..errors import ModelError
from .gravity import GRAVITATIONAL_CONSTANT
from .nbody import Bodies

__all__ = ["colliding_disks", "disk_galaxy", "plummer_sphere"]

#: Plummer radii are drawn for enclosed-mass fractions below this: the outermost 0.1% of the
#: mass (beyond 38.7 scale radii) would only add a few far-flung bodies.
PLUMMER_MASS_CUT = 0.999

#: Inner edge of a disk galaxy's disk, as a fraction of its radius (inside it the central
#: mass dominates and orbits would need tiny steps).
DISK_INNER_FRACTION = 0.1


def _unit_vectors(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` directions uniform on the sphere, shape ``(n, 3)``."""
    cos_polar = rng.uniform(-1.0, 1.0, n)
    azimuth = rng.uniform(0.0, 2.0 * math.pi, n)
    sin_polar = np.sqrt(1.0 - cos_polar**2)
    return np.stack([sin_polar * np.cos(azimuth), sin_polar * np.sin(azimuth), cos_polar], axis=1)


def _plummer_speed_fractions(rng: np.random.Generator, n: int) -> np.ndarray:
    """``q = v / v_escape`` with density ``∝ q² (1 − q²)^{7/2}``, by von Neumann rejection."""
    fractions = np.empty(n)
    missing = np.arange(n)
    while missing.size:
        q = rng.uniform(0.0, 1.0, missing.size)
        height = rng.uniform(0.0, 0.1, missing.size)  # the density peaks at 0.092
        accepted = height < q**2 * (1.0 - q**2) ** 3.5
        fractions[missing[accepted]] = q[accepted]
        missing = missing[~accepted]
    return fractions


def _centre_of_mass_frame(
    positions: np.ndarray, velocities: np.ndarray, masses: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    total = masses.sum()
    if total == 0.0:
        return positions, velocities
    return positions - masses @ positions / total, velocities - masses @ velocities / total


def plummer_sphere(
    n: int,
    *,
    total_mass: float,
    scale_radius: float,
    G: float = GRAVITATIONAL_CONSTANT,
    seed: int | np.random.Generator = 0,
) -> Bodies:
    """A Plummer star cluster of ``n`` equal masses in virial equilibrium.

    Density ``ρ(r) = 3M/(4π a³) (1 + r²/a²)^{-5/2}`` (Plummer 1911), sampled as by Aarseth,
    Hénon & Wielen (1974, A&A 37, 183): the radius from the enclosed-mass fraction
    ``X = r³/(r² + a²)^{3/2}`` uniform (below :data:`PLUMMER_MASS_CUT`), the speed from the
    isotropic distribution function, ``v = q v_esc(r)`` with ``v_esc = √2 (G M)^{1/2}
    (r² + a²)^{-1/4}`` and ``q`` drawn with density ``∝ q² (1 − q²)^{7/2}``, directions
    uniform. The sample is shifted to its centre-of-mass frame (zero total momentum). It is in
    equilibrium in expectation, not exactly: the virial ratio ``K/|U|`` is ½ up to sampling
    noise of order ``1/√n``.

    Args:
        n: Number of bodies, at least 1.
        total_mass: ``M`` [kg].
        scale_radius: ``a`` [m]; half the mass lies within 1.305 a.
        G: Constant of gravitation [m³/(kg s²)]; with ``G = M = a = 1`` the crossing time is
            of order 1 (N-body units, with ``a`` = 3π/16 of the standard unit length).
        seed: Seed or generator for ``numpy.random.default_rng``.

    Example:
        >>> import visviva as vv
        >>> cluster = vv.mechanics.plummer_sphere(1000, total_mass=1.0, scale_radius=1.0, G=1.0)
        >>> cluster.count, bool(abs(cluster.momentum()).max() < 1e-15)
        (1000, True)
    """
    count = whole_number("n", n, minimum=1)
    mass = real_number("total_mass", total_mass, positive=True, unit=" kg")
    a = real_number("scale_radius", scale_radius, positive=True, unit=" m")
    gravity = real_number("G", G, positive=True)
    rng = np.random.default_rng(seed)
    fraction = rng.uniform(0.0, PLUMMER_MASS_CUT, count)
    with np.errstate(divide="ignore"):  # X = 0 is the centre, r = 0
        radius = a / np.sqrt(fraction ** (-2.0 / 3.0) - 1.0)
    positions = radius[:, None] * _unit_vectors(rng, count)
    escape = math.sqrt(2.0 * gravity * mass) * (radius**2 + a * a) ** -0.25
    speed = _plummer_speed_fractions(rng, count) * escape
    velocities = speed[:, None] * _unit_vectors(rng, count)
    masses = np.full(count, mass / count)
    positions, velocities = _centre_of_mass_frame(positions, velocities, masses)
    return Bodies(positions, velocities, masses, gravity)


def _plane_basis(normal: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors ``(e1, e2, n)`` with ``e1 × e2 = n``; ``e1 = x̂`` for ``n = ŷ``."""
    vector = np.asarray(normal, dtype=np.float64)
    length = float(np.linalg.norm(vector)) if vector.shape == (3,) else 0.0
    if not (math.isfinite(length) and length > 0.0):
        raise ModelError(f"`normal` must be a finite, non-zero 3-vector (got {normal!r})")
    n = vector / length
    helper = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = np.cross(n, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n, e1), n


def _vector(name: str, value: Any) -> np.ndarray:
    array = np.asarray(value, dtype=np.float64)
    if array.shape != (3,) or not np.isfinite(array).all():
        raise ModelError(f"`{name}` must be a finite 3-vector (got {value!r})")
    return array


def disk_galaxy(
    n: int,
    *,
    central_mass: float,
    disk_mass: float,
    radius: float,
    G: float = GRAVITATIONAL_CONSTANT,
    softening: float = 0.0,
    center: Any = (0.0, 0.0, 0.0),
    velocity: Any = (0.0, 0.0, 0.0),
    normal: Any = (0.0, 1.0, 0.0),
    seed: int | np.random.Generator = 0,
) -> Bodies:
    """A central mass (body 0) and a flat disk of ``n`` bodies on circular orbits around it.

    Disk bodies share ``disk_mass`` equally and are spread uniformly in radius between
    :data:`DISK_INNER_FRACTION` ``· radius`` and ``radius`` (surface density ``∝ 1/r``),
    uniformly in angle, and move counter-clockwise about ``normal`` at the circular speed of
    the mass inside their radius, ``v² = G M(<r) r² / (r² + ε²)^{3/2}`` (the disk's own mass
    counted as if it were spherical: exact for ``disk_mass = 0``, the massless rings of Toomre &
    Toomre 1972, and a fair start while the disk is light next to the centre).

    Args:
        n: Number of disk bodies, at least 1.
        central_mass: [kg], positive. disk_mass: [kg], zero or positive.
        radius: Outer radius of the disk [m].
        G: Constant of gravitation [m³/(kg s²)].
        softening: The Plummer softening the simulation will use [m] (enters ``v``).
        center, velocity: Centre of mass [m] and its velocity [m/s] of the whole galaxy.
        normal: Axis of rotation (the disk's normal); +y by default (Y up).
        seed: Seed or generator for ``numpy.random.default_rng``.
    """
    count = whole_number("n", n, minimum=1)
    centre_mass = real_number("central_mass", central_mass, positive=True, unit=" kg")
    disk = real_number("disk_mass", disk_mass, nonnegative=True)
    outer = real_number("radius", radius, positive=True, unit=" m")
    gravity = real_number("G", G, positive=True)
    eps = real_number("softening", softening, nonnegative=True)
    e1, e2, _ = _plane_basis(normal)
    rng = np.random.default_rng(seed)
    inner = DISK_INNER_FRACTION * outer
    r = rng.uniform(inner, outer, count)
    angle = rng.uniform(0.0, 2.0 * math.pi, count)
    enclosed = centre_mass + disk * (r - inner) / (outer - inner)
    speed = np.sqrt(gravity * enclosed * r**2 / (r**2 + eps**2) ** 1.5)
    cos, sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
    positions = r[:, None] * (cos * e1 + sin * e2)
    velocities = speed[:, None] * (-sin * e1 + cos * e2)
    masses = np.concatenate([[centre_mass], np.full(count, disk / count)])
    positions = np.vstack([np.zeros(3), positions])
    velocities = np.vstack([np.zeros(3), velocities])
    # The disk's mass centre and momentum are zero only on average: move the central body so
    # that the galaxy's centre of mass is exactly `center` and its momentum exactly M·velocity.
    positions[0] -= masses[1:] @ positions[1:] / centre_mass
    velocities[0] -= masses[1:] @ velocities[1:] / centre_mass
    return Bodies(
        positions + _vector("center", center),
        velocities + _vector("velocity", velocity),
        masses,
        gravity,
    )


def colliding_disks(
    n_per_disk: int,
    *,
    central_mass: float,
    disk_mass: float,
    radius: float,
    separation: float,
    pericenter: float,
    inclination: float = math.radians(60.0),
    G: float = GRAVITATIONAL_CONSTANT,
    softening: float = 0.0,
    seed: int | np.random.Generator = 0,
) -> Bodies:
    """Two equal disk galaxies falling towards each other on a parabolic orbit.

    The galaxies (see :func:`disk_galaxy`) start ``separation`` apart on the zero-energy
    orbit of their total masses that would bring their centres within ``pericenter`` of each
    other (Toomre & Toomre 1972): the first disk turns with the orbit (in the x–z plane,
    counter-clockwise seen from +y), the second is tilted by ``inclination`` about the x axis.
    Bodies: the first galaxy's centre, its disk, then the second's centre and disk. Total
    momentum is zero.

    Args:
        n_per_disk: Disk bodies per galaxy, at least 1.
        central_mass, disk_mass, radius, G, softening, seed: As for :func:`disk_galaxy`.
        separation: Initial distance between the centres [m], at least ``pericenter``.
        pericenter: Closest approach of the centres [m], positive.
        inclination: Tilt of the second disk [rad].

    Example:
        >>> import visviva as vv
        >>> bodies = vv.mechanics.colliding_disks(
        ...     100, central_mass=1.0, disk_mass=0.0, radius=1.0, separation=8.0,
        ...     pericenter=2.0, G=1.0, softening=0.05)
        >>> bodies.count, bool(abs(bodies.momentum()).max() < 1e-15)
        (202, True)
    """
    d = real_number("separation", separation, positive=True, unit=" m")
    q = real_number("pericenter", pericenter, positive=True, unit=" m")
    tilt = real_number("inclination", inclination, unit=" rad")
    if d < q:
        raise ModelError(
            f"`separation` ({d!r} m) must be at least `pericenter` ({q!r} m): the galaxies "
            "start on the orbit that reaches the pericenter later"
        )
    galaxy_mass = real_number("central_mass", central_mass, positive=True) + real_number(
        "disk_mass", disk_mass, nonnegative=True
    )
    mu = real_number("G", G, positive=True) * 2.0 * galaxy_mass
    # Parabola r = 2q / (1 + cos f), before pericenter (f < 0); h = √(2 μ q).
    f = -math.acos(2.0 * q / d - 1.0)
    h = math.sqrt(2.0 * mu * q)
    radial, transverse = mu / h * math.sin(f), mu / h * (1.0 + math.cos(f))
    direction = np.array([math.cos(f), 0.0, -math.sin(f)])  # (x, z) = (ξ, −η)
    across = np.array([-math.sin(f), 0.0, -math.cos(f)])
    relative_position = d * direction
    relative_velocity = radial * direction + transverse * across
    galaxy = functools.partial(
        disk_galaxy,
        n_per_disk,
        central_mass=central_mass,
        disk_mass=disk_mass,
        radius=radius,
        G=G,
        softening=softening,
        seed=np.random.default_rng(seed),
    )
    first = galaxy(center=-0.5 * relative_position, velocity=-0.5 * relative_velocity)
    second = galaxy(
        center=0.5 * relative_position,
        velocity=0.5 * relative_velocity,
        normal=(0.0, math.cos(tilt), math.sin(tilt)),
    )
    return Bodies(
        np.vstack([first.positions, second.positions]),
        np.vstack([first.velocities, second.velocities]),
        np.concatenate([first.masses, second.masses]),
        first.G,
    )
