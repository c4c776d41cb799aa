"""Force fields on particles: gravity, drag and wind, quadratic drag, damping, attractors, vortices.

Each class follows :class:`~visviva.forces.base.Force` and acts on a set of target particles;
the laws and their derivation are in :mod:`visviva.forces.laws`. Every field acts on each
particle from that particle's own state, so its Jacobians are 3×3 blocks on the diagonal.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numba import njit

from .._validation import real_number
from ..errors import ModelError
from .base import Targets, diagonal_blocks
from .laws import (
    ATTRACTOR,
    DAMPING,
    DRAG,
    GRAVITY,
    QUADRATIC_DRAG,
    VORTEX,
    FieldLaw,
    attractor_jacobian,
    attractor_potential,
    field_forces,
    law_row,
    quadratic_drag_jacobian,
    vortex_jacobian,
)

if TYPE_CHECKING:
    from ..ode.workspace import Workspace

__all__ = ["Attractor", "Damping", "Drag", "QuadraticDrag", "UniformGravity", "Vortex", "vector"]

_NO_BLOCKS = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))


def vector(name: str, value: Sequence[float], *, unit: str, nonzero: bool = False) -> np.ndarray:
    """``value`` as a finite 3-vector, refused with its name if it is not one."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        array = np.full(0, np.nan)
    if array.shape != (3,) or not np.isfinite(array).all():
        raise ModelError(f"`{name}` must be three finite numbers [{unit}] (got {value!r})")
    if nonzero and not np.any(array):
        raise ModelError(f"`{name}` must not be the zero vector (it gives a direction)")
    return array


class _Field:
    """Common part of the fields: targets, masses, the diagonal block pattern, and the force
    itself, evaluated by the field's law (:func:`~.laws.field_force`, the law the fused particle
    step evaluates too)."""

    conservative: ClassVar[bool] = False
    velocity_dependent: ClassVar[bool] = True
    #: The code of its law (:mod:`.laws`).
    law: ClassVar[int]

    def __init__(self, mass: np.ndarray, targets: Targets) -> None:
        self.mass = np.asarray(mass, dtype=np.float64)
        self.targets = targets

    def law_parameters(self) -> tuple[float, ...]:
        """The row of its law's parameters (see :mod:`.laws`)."""
        raise NotImplementedError

    @property
    def compiled(self) -> FieldLaw:
        """Its compiled form: its law, parameters and targets."""
        return FieldLaw(self.law, self.law_parameters(), self.targets)

    def accumulate(
        self, t: float, x: np.ndarray, v: np.ndarray, out: np.ndarray, work: Workspace | None = None
    ) -> None:
        """Add the field's force [N] on every target to ``out`` ``(N, 3)``."""
        row = law_row(self.law_parameters())
        field_forces(self.law, row, self.targets.indices, x, v, self.mass, out)

    @property
    def linear_damping(self) -> bool:
        """No linear damper (a damping field says otherwise)."""
        return False

    def potential(self, t: float, x: np.ndarray, alive: np.ndarray | None = None) -> float:
        """Potential energy [J]: none for a dissipative field."""
        return 0.0

    def jacobian_blocks(self) -> tuple[np.ndarray, np.ndarray] | None:
        """One 3×3 block per target particle, on the diagonal."""
        return diagonal_blocks(self.targets)


class UniformGravity(_Field):
    """Constant gravitational acceleration: ``F = m g``, ``U = −m g·x`` (zero at the origin).

    Args:
        gravity: Acceleration ``g`` [m/s²], shape ``(3,)`` (Y up: ``(0, −9.81, 0)`` on Earth).
        mass: Particle masses [kg], shape ``(N,)``.
        targets: The particles it acts on (default: all).
    """

    conservative = True
    velocity_dependent = False
    law = GRAVITY

    def __init__(
        self, gravity: Sequence[float], mass: np.ndarray, targets: Targets | None = None
    ) -> None:
        super().__init__(mass, targets or Targets(len(mass)))
        self.gravity = vector("gravity", gravity, unit="m/s²")
        # m_i g for every target, once (the potential's).
        self._weight = self.mass[self.targets.indices, None] * self.gravity[None, :]

    def law_parameters(self) -> tuple[float, ...]:
        return tuple(self.gravity)

    def potential(self, t: float, x: np.ndarray, alive: np.ndarray | None = None) -> float:
        """``U = −Σ_i m_i g·x_i`` [J] over the targets (alive ones, if given)."""
        if alive is None:
            return -float(np.einsum("ij,ij->", x[self.targets.indices], self._weight))
        keep = alive[self.targets.indices]
        return -float(np.einsum("ij,ij->", x[self.targets.indices[keep]], self._weight[keep]))

    def jacobian_blocks(self) -> tuple[np.ndarray, np.ndarray] | None:
        """No blocks: the force does not change with the state."""
        return _NO_BLOCKS

    def add_jacobian(self, t, x, v, dfdx, dfdv, form="exact") -> None:  # type: ignore[no-untyped-def]
        """Nothing to add: ``∂F/∂x = ∂F/∂v = 0``."""


class _AirDrag(_Field):
    """A drag towards the air's velocity: a coefficient and the air velocity ``w`` [m/s]."""

    def __init__(
        self,
        coefficient: float,
        mass: np.ndarray,
        targets: Targets | None = None,
        air_velocity: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> None:
        super().__init__(mass, targets or Targets(len(mass)))
        self.coefficient = real_number("coefficient", coefficient, nonnegative=True)
        self.air_velocity = vector("velocity", air_velocity, unit="m/s")


class Drag(_AirDrag):
    """Linear drag in still or moving air: ``F = −k (v − w)`` (wind when ``w ≠ 0``).

    Args:
        coefficient: ``k`` [N·s/m], at least 0.
        mass: Particle masses [kg] (unused by the law; kept for the common interface).
        targets: The particles it acts on (default: all).
        air_velocity: The air's velocity ``w`` [m/s].
    """

    @property
    def linear_damping(self) -> bool:
        """In still air the drag is ``D v`` with ``D = −k I`` (see visviva.forces.ForceSum)."""
        return not np.any(self.air_velocity)

    law = DRAG

    def law_parameters(self) -> tuple[float, ...]:
        return (*(float(w) for w in self.air_velocity), self.coefficient)

    def add_jacobian(self, t, x, v, dfdx, dfdv, form="exact") -> None:  # type: ignore[no-untyped-def]
        """``∂F/∂v = −k I`` [N·s/m] on each block."""
        for axis in range(3):
            dfdv[:, axis, axis] -= self.coefficient


class Damping(_Field):
    """Mass-proportional damping ``F = −γ m v``: every particle slows at the rate ``γ`` [1/s].

    Args:
        rate: ``γ`` [1/s], at least 0.
        mass: Particle masses [kg], shape ``(N,)``.
        targets: The particles it acts on (default: all).
    """

    @property
    def linear_damping(self) -> bool:
        """``F = D v`` with ``D = −γ m I`` (see visviva.forces.ForceSum)."""
        return True

    law = DAMPING

    def __init__(self, rate: float, mass: np.ndarray, targets: Targets | None = None) -> None:
        super().__init__(mass, targets or Targets(len(mass)))
        self.rate = real_number("rate", rate, nonnegative=True, unit=" 1/s")
        self._factor = (self.rate * self.mass[self.targets.indices])[:, None]

    def law_parameters(self) -> tuple[float, ...]:
        return (self.rate,)

    def add_jacobian(self, t, x, v, dfdx, dfdv, form="exact") -> None:  # type: ignore[no-untyped-def]
        """``∂F/∂v = −γ m I`` [kg/s] on each block."""
        for axis in range(3):
            dfdv[:, axis, axis] -= self._factor[:, 0]


class QuadraticDrag(_AirDrag):
    """Quadratic drag ``F = −c |v − w| (v − w)``, the drag of a fast body in air.

    Args:
        coefficient: ``c`` [kg/m] (``½ ρ C_d A``), at least 0.
        mass: Particle masses [kg] (unused by the law).
        targets: The particles it acts on (default: all).
        air_velocity: The air's velocity ``w`` [m/s].
    """

    law = QUADRATIC_DRAG

    def law_parameters(self) -> tuple[float, ...]:
        return (*(float(w) for w in self.air_velocity), self.coefficient)

    def add_jacobian(self, t, x, v, dfdx, dfdv, form="exact") -> None:  # type: ignore[no-untyped-def]
        """``∂F/∂v`` [kg/s] on each block (see :func:`~.laws.quadratic_drag_jacobian`)."""
        _quadratic_drag_blocks(self.targets.indices, v, *self.air_velocity, self.coefficient, dfdv)


class Attractor(_Field):
    """A point attractor (or repulsor), softened inverse square: ``F = −s m d / ρ³``.

    Args:
        point: The centre ``c`` [m].
        strength: ``s`` [m³/s²]: ``G M`` of the attracting mass; negative repels.
        mass: Particle masses [kg], shape ``(N,)``.
        targets: The particles it acts on (default: all).
        softening: ``ε`` [m] > 0: caps the force near the centre at about ``s m / ε²``.
    """

    conservative = True
    velocity_dependent = False

    def __init__(
        self,
        point: Sequence[float],
        strength: float,
        mass: np.ndarray,
        targets: Targets | None = None,
        softening: float = 0.1,
    ) -> None:
        super().__init__(mass, targets or Targets(len(mass)))
        self.point = vector("point", point, unit="m")
        self.strength = real_number("strength", strength, unit=" m³/s²")
        self.softening = real_number("softening", softening, positive=True, unit=" m")

    law = ATTRACTOR

    def law_parameters(self) -> tuple[float, ...]:
        return (*(float(c) for c in self.point), self.strength, self.softening**2)

    def potential(self, t: float, x: np.ndarray, alive: np.ndarray | None = None) -> float:
        """``U = −Σ_i s m_i / ρ_i`` [J] over the targets (alive ones, if given)."""
        return float(
            _attractor_energy(self.targets.mask(alive), x, self.mass, *self.law_parameters())
        )

    def add_jacobian(self, t, x, v, dfdx, dfdv, form="exact") -> None:  # type: ignore[no-untyped-def]
        """``∂F/∂x`` [N/m] on each block (see :func:`~.laws.attractor_jacobian`)."""
        _attractor_blocks(self.targets.indices, x, self.mass, *self.law_parameters(), dfdx)


class Vortex(_Field):
    """Air swirling about an axis, dragging particles along: ``F = k (u(x) − v)``.

    Args:
        point: A point ``c`` [m] on the vortex's axis.
        axis: The axis direction (any length); the air turns counter-clockwise about it.
        circulation: ``Γ`` [m²/s]: the air's speed at distance ``r`` (outside the core) is
            ``Γ / (2π r)``.
        coefficient: ``k`` [N·s/m] of the drag towards the air's velocity, at least 0.
        mass: Particle masses [kg] (unused by the law).
        targets: The particles it acts on (default: all).
        core_radius: ``r`` [m] > 0: inside it the air turns like a solid body.
    """

    def __init__(
        self,
        point: Sequence[float],
        axis: Sequence[float],
        circulation: float,
        coefficient: float,
        mass: np.ndarray,
        targets: Targets | None = None,
        core_radius: float = 0.5,
    ) -> None:
        super().__init__(mass, targets or Targets(len(mass)))
        self.point = vector("point", point, unit="m")
        direction = vector("axis", axis, unit="", nonzero=True)
        self.axis = direction / np.linalg.norm(direction)
        self.circulation = real_number("circulation", circulation, unit=" m²/s")
        self.coefficient = real_number("coefficient", coefficient, nonnegative=True)
        self.core_radius = real_number("core_radius", core_radius, positive=True, unit=" m")

    law = VORTEX

    def law_parameters(self) -> tuple[float, ...]:
        factor = self.circulation / (2.0 * math.pi)
        point, axis = (float(c) for c in self.point), (float(a) for a in self.axis)
        return (*point, *axis, factor, self.core_radius**2, self.coefficient)

    def add_jacobian(self, t, x, v, dfdx, dfdv, form="exact") -> None:  # type: ignore[no-untyped-def]
        """``∂F/∂x = k ∂u/∂x`` and ``∂F/∂v = −k I`` on each block."""
        _vortex_blocks(self.targets.indices, x, *self.law_parameters(), dfdx)
        for axis in range(3):
            dfdv[:, axis, axis] -= self.coefficient


# Serial loops over the targets (see visviva.forces.base for why not parallel).


@njit(cache=True, error_model="numpy")
def _quadratic_drag_blocks(index, v, wx, wy, wz, c, dfdv):  # pragma: no cover - compiled
    for b in range(index.shape[0]):
        i = index[b]
        quadratic_drag_jacobian(v[i, 0], v[i, 1], v[i, 2], wx, wy, wz, c, dfdv[b])


@njit(cache=True, error_model="numpy")
def _attractor_energy(index, x, m, cx, cy, cz, s, eps2):  # pragma: no cover - compiled
    total = 0.0
    for i in index:
        total += attractor_potential(x[i, 0], x[i, 1], x[i, 2], cx, cy, cz, s, eps2, m[i])
    return total


@njit(cache=True, error_model="numpy")
def _attractor_blocks(index, x, m, cx, cy, cz, s, eps2, dfdx):  # pragma: no cover - compiled
    for b in range(index.shape[0]):
        i = index[b]
        attractor_jacobian(x[i, 0], x[i, 1], x[i, 2], cx, cy, cz, s, eps2, m[i], dfdx[b])


@njit(cache=True, error_model="numpy")
def _vortex_blocks(index, x, cx, cy, cz, ax, ay, az, f, core2, k, dfdx):  # pragma: no cover
    for b in range(index.shape[0]):
        i = index[b]
        vortex_jacobian(x[i, 0], x[i, 1], x[i, 2], cx, cy, cz, ax, ay, az, f, core2, k, dfdx[b])
