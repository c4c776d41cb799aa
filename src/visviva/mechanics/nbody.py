"""N-body problems for the shared pipeline: gravitating bodies as a second-order problem.

The state is the foundation's split ``(q, v)`` with ``q`` the positions flattened body by body,
``q = (x0, y0, z0, x1, y1, z1, ...)`` of length ``3N`` (``(batch, 3N)`` for a batch of systems
sharing the masses). The acceleration depends on positions only, so symplectic methods
(``velocity_verlet``, ``leapfrog``) keep their properties, and every integrator, the recorder
and the outputs work on it unchanged. Initial conditions come as :class:`Bodies` from
:mod:`visviva.mechanics.kepler` and :mod:`visviva.mechanics.clusters`.

Few bodies (at most :data:`COMPILED_MAX_BODIES`, direct summation) get an acceleration compiled
with Numba that describes one system, so :func:`visviva.solve` runs the whole time loop in
compiled code: a million Kepler steps take a fraction of a second once compiled (about a second
per new set of masses, kept for the session). More bodies use the parallel kernels of
:mod:`visviva.mechanics.gravity`, called once per step.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._memo import Memo
from .._validation import real_number
from ..errors import ModelError
from ..ode.problems import SecondOrderProblem
from .gravity import (
    GRAVITATIONAL_CONSTANT,
    PointMasses,
    accelerations_into,
    body_acceleration,
    check_masses,
    check_method,
    check_positions,
    gravity_accelerations,
    potential_energy,
    row_potential,
)

__all__ = ["COMPILED_MAX_BODIES", "Bodies", "nbody_problem"]

#: Systems of at most this many bodies (direct summation) get a compiled one-system
#: acceleration: below it, the cost of a step is Python overhead, not arithmetic.
COMPILED_MAX_BODIES = 8

#: Compiled few-body functions by masses, G and softening, the most recently used kept.
_COMPILED: Memo[tuple[Callable[..., None], Callable[..., float]]] = Memo(32)


@dataclass(frozen=True)
class Bodies:
    """Point masses with their state: initial conditions for :func:`nbody_problem`.

    Attributes:
        positions: Positions [m], shape ``(N, 3)``.
        velocities: Velocities [m/s], shape ``(N, 3)``.
        masses: Masses [kg], shape ``(N,)``.
        G: The constant of gravitation these were set up with [m³/(kg s²)].
        names: A name per body, or empty.
    """

    positions: np.ndarray
    velocities: np.ndarray
    masses: np.ndarray
    G: float = GRAVITATIONAL_CONSTANT
    names: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        positions = check_positions("positions", self.positions)
        count = positions.shape[0]
        velocities = _checked_velocities(self.velocities, (count, 3))
        masses = check_masses(self.masses, count)
        for field, value in (("positions", positions), ("velocities", velocities)):
            object.__setattr__(self, field, _read_only(value))
        object.__setattr__(self, "masses", _read_only(masses))
        object.__setattr__(self, "G", real_number("G", self.G, positive=True))
        if self.names and len(self.names) != count:
            raise ModelError(f"`names` must name all {count} bodies (got {len(self.names)})")
        object.__setattr__(self, "names", tuple(self.names))

    @property
    def count(self) -> int:
        """Number of bodies ``N``."""
        return int(self.masses.shape[0])

    def momentum(self) -> np.ndarray:
        """Total linear momentum ``Σ m_i v_i`` [kg·m/s], shape ``(3,)``."""
        return self.masses @ self.velocities

    def kinetic_energy(self) -> float:
        """``½ Σ m_i |v_i|²`` [J]."""
        return 0.5 * float(self.masses @ (self.velocities**2).sum(axis=1))

    def problem(
        self,
        *,
        softening: float = 0.0,
        method: str = "direct",
        theta: float = 0.5,
        name: str = "n-body",
    ) -> SecondOrderProblem:
        """These bodies as a second-order problem (see :func:`nbody_problem`)."""
        return nbody_problem(
            self.positions,
            self.velocities,
            self.masses,
            G=self.G,
            softening=softening,
            method=method,
            theta=theta,
            name=name,
        )


def _read_only(array: np.ndarray) -> np.ndarray:
    copy = np.array(array, dtype=np.float64)
    copy.setflags(write=False)
    return copy


def _checked_velocities(velocities: Any, shape: tuple[int, ...]) -> np.ndarray:
    try:
        array = np.asarray(velocities, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ModelError(f"`velocities` must be an array of numbers of shape {shape}") from exc
    if array.shape != shape:
        raise ModelError(
            f"`velocities` must have the shape of `positions` {shape} (got {array.shape})"
        )
    bad = ~np.isfinite(array)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ModelError(f"`velocities` must be finite (entry {index} is {array[index]!r})")
    return array


def _checked_state(
    positions: Any, velocities: Any, masses: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """Positions and velocities as ``(batch, N, 3)``, masses ``(N,)``, and whether batched."""
    try:
        array = np.asarray(positions, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ModelError("`positions` must be an (N, 3) array of numbers [m]") from exc
    if array.ndim not in (2, 3):
        raise ModelError(
            "`positions` must have shape (N, 3), or (batch, N, 3) for a batch of systems "
            f"(got shape {array.shape})"
        )
    batched = array.ndim == 3
    systems = array if batched else array[None]
    checked = np.stack([check_positions("positions", system) for system in systems])
    velocity = _checked_velocities(velocities, array.shape).reshape(checked.shape)
    mass = check_masses(masses, checked.shape[1])
    return checked, velocity, mass, batched


def _compiled_functions(
    masses: np.ndarray, G: float, eps2: float
) -> tuple[Callable[..., None], Callable[..., float]]:
    """``acceleration(t, q, out)`` and ``energy(t, q, v)`` for one system of few bodies.

    Numba closures over the direct method's own pair sums
    (:func:`~visviva.mechanics.gravity.body_acceleration`,
    :func:`~visviva.mechanics.gravity.row_potential`), with the masses frozen in as constants
    (one compilation per set of masses, kept for the session), so the compiled whole-run loop
    can call them. With ``eps2 = 0`` two bodies meeting exactly give a non-finite
    acceleration, which the simulation's divergence watch reports.
    """
    key = (tuple(float(m) for m in masses), G, eps2)

    def build() -> tuple[Callable[..., None], Callable[..., float]]:
        import numba

        bodies = PointMasses(np.zeros((len(key[0]), 3)), np.array(key[0]), 0.0)
        m, scaled, row_mass = np.array(key[0]), bodies.mass, bodies.row_mass
        factor = G * bodies.mass_scale
        potential_factor = factor * bodies.mass_scale
        n = m.shape[0]

        @numba.njit(error_model="numpy")
        def acceleration(t, q, out):  # pragma: no cover - compiled
            x, y, z = q[0::3], q[1::3], q[2::3]
            for i in range(n):
                ax, ay, az, _ = body_acceleration(x, y, z, scaled, row_mass, eps2, factor, i)
                out[3 * i] = ax
                out[3 * i + 1] = ay
                out[3 * i + 2] = az

        @numba.njit(error_model="numpy")
        def energy(t, q, v):  # pragma: no cover - compiled
            x, y, z = q[0::3], q[1::3], q[2::3]
            total = 0.0
            for i in range(n):
                speed2 = v[3 * i] ** 2 + v[3 * i + 1] ** 2 + v[3 * i + 2] ** 2
                pairs, _ = row_potential(x, y, z, scaled, eps2, i)
                total += 0.5 * m[i] * speed2 - potential_factor * pairs
            return total

        return acceleration, energy

    return _COMPILED.get(key, build)


def nbody_problem(
    positions: Any,
    velocities: Any,
    masses: Any,
    *,
    G: float = GRAVITATIONAL_CONSTANT,
    softening: float = 0.0,
    method: str = "direct",
    theta: float = 0.5,
    name: str = "n-body",
) -> SecondOrderProblem:
    """Bodies under their mutual gravitation, as a problem for :func:`visviva.solve`.

    Args:
        positions: Initial positions [m], shape ``(N, 3)``, or ``(batch, N, 3)`` for a batch of
            systems with the same masses.
        velocities: Initial velocities [m/s], the shape of ``positions``.
        masses: Masses [kg], shape ``(N,)``, zero (test particle) or positive.
        G, softening, method, theta: As for
            :func:`~visviva.mechanics.gravity.gravity_accelerations`.
        name: Short description used in messages and recordings.

    Returns:
        A :class:`~visviva.ode.SecondOrderProblem` with ``q`` the positions flattened to
        ``(3N,)`` (``(batch, 3N)``), the position-only ``acceleration(t, q, out)`` and
        ``energy(t, q, v)`` = kinetic + potential [J] (with ``"barnes_hut"``, the tree's
        potential, whose error is of the order of the force error).

    Raises:
        ModelError: For invalid input, including coincident bodies without softening.

    Example:
        >>> import numpy as np, visviva as vv
        >>> problem = vv.mechanics.nbody_problem(
        ...     [[-0.5, 0, 0], [0.5, 0, 0]], [[0, 0, -0.5], [0, 0, 0.5]], [0.5, 0.5], G=1.0
        ... )
        >>> sol = vv.solve(problem, "velocity_verlet", dt=0.01, until=2 * np.pi)
        >>> bool(np.abs(sol.q[-1] - sol.q[0]).max() < 1e-3)  # one circular orbit
        True
    """
    x, v, m, batched = _checked_state(positions, velocities, masses)
    gravity = real_number("G", G, positive=True, unit=" m³/(kg s²)")
    epsilon = real_number("softening", softening, nonnegative=True)
    method, theta = check_method(method, theta)
    count = m.shape[0]
    shape = (x.shape[0], 3 * count) if batched else (3 * count,)
    compiled = method == "direct" and count <= COMPILED_MAX_BODIES
    if compiled:
        for system in x:  # the compiled acceleration cannot name coincident bodies itself
            gravity_accelerations(system, m, G=gravity, softening=epsilon)
        acceleration, energy = _compiled_functions(m, gravity, epsilon**2)
    else:
        acceleration = _kernel_acceleration(m, gravity, epsilon, method, theta)
        energy = _energy_function(m, gravity, epsilon, method, theta)
    return SecondOrderProblem(
        acceleration,
        x.reshape(shape),
        v.reshape(shape),
        energy=energy,
        name=str(name),
    )


def _systems(array: np.ndarray, count: int) -> np.ndarray:
    """A ``(3N,)`` or ``(batch, 3N)`` state as ``(systems, N, 3)``."""
    return array.reshape(-1, count, 3)


def _kernel_acceleration(
    masses: np.ndarray, G: float, softening: float, method: str, theta: float
) -> Callable[..., None]:
    count = masses.shape[0]

    def acceleration(t: float, q: np.ndarray, out: np.ndarray) -> None:
        result = np.empty((count, 3))
        flat = out.reshape(-1, 3 * count)
        for index, system in enumerate(_systems(q, count)):
            bodies = PointMasses(system, masses, softening)
            accelerations_into(bodies, G, method, theta, result)
            flat[index] = result.reshape(-1)
        if not np.shares_memory(flat, out):
            out[...] = flat.reshape(out.shape)

    return acceleration


def _energy_function(
    masses: np.ndarray, G: float, softening: float, method: str, theta: float
) -> Callable[..., Any]:
    count = masses.shape[0]

    def energy(t: float, q: np.ndarray, v: np.ndarray) -> Any:
        velocities = _systems(v, count)
        kinetic = 0.5 * np.einsum("i,sij,sij->s", masses, velocities, velocities)
        potential = np.array(
            [
                potential_energy(PointMasses(system, masses, softening), G, method, theta)
                for system in _systems(q, count)
            ]
        )
        total = kinetic + potential
        return total if q.ndim == 2 else float(total[0])

    return energy
