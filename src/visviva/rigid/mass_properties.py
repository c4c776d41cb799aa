"""Mass properties of a rigid body: mass, centre of mass and inertia tensor, checked once.

:class:`MassProperties` holds what the dynamics of a rigid body needs from its shape and
density: the mass ``m`` [kg], where the centre of mass lies in the shape's coordinates [m], and
the inertia tensor about the centre of mass in the shape's axes [kg·m²],

    I = ∫ ρ (|r|² E − r rᵀ) dV,   r measured from the centre of mass,

with ``E`` the 3 × 3 identity. It is refused at construction unless it could belong to a real
body: a positive finite mass, and an inertia tensor that is symmetric and positive definite
with principal moments obeying the triangle inequality I₁ + I₂ ≥ I₃ (for principal axes
e₁, e₂, e₃, I₁ + I₂ − I₃ = 2 ∫ ρ (r·e₃)² dV ≥ 0, with equality only for a flat body).

The tensor is moved rather than recomputed: :meth:`MassProperties.about` gives it about another
point by the parallel-axis theorem (Huygens–Steiner), J = I + m (|d|² E − d dᵀ);
:meth:`MassProperties.rotated` and :meth:`MassProperties.translated` give the properties of the
moved shape (I' = R I Rᵀ); :meth:`MassProperties.principal` the principal moments and axes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validation import describe, real_number
from ..errors import ModelError

__all__ = [
    "ROTATION_TOLERANCE",
    "SYMMETRY_TOLERANCE",
    "TRIANGLE_TOLERANCE",
    "MassProperties",
    "check_inertia",
]

#: Largest accepted |Iⱼₖ − Iₖⱼ| as a fraction of the largest |Iⱼₖ|: rounding in a tensor that was
#: computed (rotated, summed) is far below it; a typing mistake is far above it. The stored
#: tensor is the symmetric part (I + Iᵀ)/2.
SYMMETRY_TOLERANCE = 1e-9
#: Principal moments may miss the triangle inequality I₁ + I₂ ≥ I₃ by this fraction of I₃: a
#: flat body (a plate) meets it with equality, which rounding can break by a few ulps.
TRIANGLE_TOLERANCE = 1e-9
#: Largest accepted entry of |RᵀR − E| for a rotation matrix given to
#: :meth:`MassProperties.rotated`.
ROTATION_TOLERANCE = 1e-9


def _matrix(name: str, value: Any) -> np.ndarray:
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ModelError(
            f"`{name}` must be a 3 × 3 array of numbers (got {describe(value)})"
        ) from exc
    if array.shape != (3, 3):
        raise ModelError(f"`{name}` must have shape (3, 3) (got shape {array.shape})")
    bad = ~np.isfinite(array)
    if bad.any():
        row, column = (int(k) for k in np.argwhere(bad)[0])
        raise ModelError(
            f"`{name}` must be finite; entry ({row}, {column}) is {describe(array[row, column])}"
        )
    return array


def _vector(name: str, value: Any, unit: str) -> np.ndarray:
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ModelError(f"`{name}` must be 3 numbers [{unit}] (got {describe(value)})") from exc
    if array.shape != (3,) or not np.isfinite(array).all():
        raise ModelError(f"`{name}` must be 3 finite numbers [{unit}] (got {describe(value)})")
    return array


def _eigen(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ascending eigenvalues and eigenvectors of a symmetric tensor, scaled so that tensors
    near the ends of float64's range neither overflow nor underflow inside LAPACK."""
    scale = float(np.max(np.abs(inertia)))
    if scale == 0.0:
        return np.zeros(3), np.eye(3)
    moments, axes = np.linalg.eigh(inertia / scale)
    return moments * scale, axes


def check_inertia(value: Any, *, name: str = "inertia") -> np.ndarray:
    """Return ``value`` as a symmetric, positive definite 3 × 3 inertia tensor, or raise.

    Args:
        value: The tensor [kg·m²], about the centre of mass.
        name: How the message names it, e.g. ``"bodies[2].inertia"``.

    Returns:
        A fresh read-only float64 ``(3, 3)`` array, the symmetric part of ``value``.

    Raises:
        ModelError: Not a finite 3 × 3 array, not symmetric (within
            :data:`SYMMETRY_TOLERANCE`), not positive definite, or principal moments that break
            the triangle inequality (within :data:`TRIANGLE_TOLERANCE`).
    """
    inertia = _matrix(name, value)
    largest = float(np.max(np.abs(inertia)))
    asymmetry = float(np.max(np.abs(inertia - inertia.T)))
    if asymmetry > SYMMETRY_TOLERANCE * largest:
        row, column = (
            int(k) for k in np.unravel_index(np.argmax(np.abs(inertia - inertia.T)), (3, 3))
        )
        raise ModelError(
            f"`{name}` must be symmetric: entry ({row}, {column}) is "
            f"{inertia[row, column]!r} but ({column}, {row}) is {inertia[column, row]!r} "
            "(an inertia tensor satisfies Iⱼₖ = Iₖⱼ; products of inertia are −∫ρ xⱼ xₖ dV)"
        )
    inertia = 0.5 * (inertia + inertia.T)
    moments, _ = _eigen(inertia)
    if not moments[0] > 0.0:
        raise ModelError(
            f"`{name}` must be positive definite: its principal moments are "
            f"{describe(moments)} kg·m², and every one must be positive (a body with a zero "
            "moment is a line of points; check the signs of the products of inertia, which "
            "are −∫ρ xⱼ xₖ dV)"
        )
    if moments[0] + moments[1] < moments[2] * (1.0 - TRIANGLE_TOLERANCE):
        raise ModelError(
            f"`{name}` breaks the triangle inequality of principal moments: I₁ + I₂ = "
            f"{moments[0] + moments[1]:.6g} < I₃ = {moments[2]:.6g} kg·m² (principal moments "
            f"{describe(moments)}); no distribution of mass has them, since I₁ + I₂ − I₃ = "
            "2∫ρ (r·e₃)² dV ≥ 0. Check the diagonal: a box of full edges a, b, c has "
            "Iₓₓ = m (b² + c²)/12, not m a²/12"
        )
    inertia.setflags(write=False)
    return inertia


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=np.float64)
    array.setflags(write=False)
    return array


def _rotation(value: Any) -> np.ndarray:
    rotation = _matrix("rotation", value)
    error = float(np.max(np.abs(rotation.T @ rotation - np.eye(3))))
    if error > ROTATION_TOLERANCE or not np.linalg.det(rotation) > 0.0:
        raise ModelError(
            "`rotation` must be a proper rotation matrix (RᵀR = E and det R = +1): "
            f"|RᵀR − E| reaches {error:.3g} and det R = {float(np.linalg.det(rotation)):.6g}; "
            "build it from a unit quaternion or orthonormal columns"
        )
    return rotation


@dataclass(frozen=True, eq=False)
class MassProperties:
    """The mass properties of a rigid body, in its shape's coordinates.

    Attributes:
        mass: Mass [kg], positive.
        center_of_mass: Centre of mass ``(3,)`` [m], in the shape's coordinates.
        inertia: Inertia tensor ``(3, 3)`` [kg·m²] about the centre of mass, in the shape's
            axes; symmetric, positive definite, principal moments obeying I₁ + I₂ ≥ I₃.
        volume: Volume [m³] of the shape, or ``None`` when the properties were given directly.

    >>> import numpy as np
    >>> rod = MassProperties(mass=2.0, center_of_mass=[0.0, 0.5, 0.0],
    ...                      inertia=np.diag([0.17, 0.01, 0.17]))
    >>> rod.about([0.0, 0.0, 0.0]).diagonal().round(6).tolist()   # I + m (|d|² E − d dᵀ)
    [0.67, 0.01, 0.67]
    """

    mass: float
    center_of_mass: np.ndarray
    inertia: np.ndarray
    volume: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "mass", real_number("mass", self.mass, positive=True, unit=" kg"))
        center = _frozen(_vector("center_of_mass", self.center_of_mass, "m"))
        object.__setattr__(self, "center_of_mass", center)
        object.__setattr__(self, "inertia", check_inertia(self.inertia))
        if self.volume is not None:
            volume = real_number("volume", self.volume, positive=True, unit=" m³")
            object.__setattr__(self, "volume", volume)

    @property
    def density(self) -> float | None:
        """Mean density [kg/m³], mass over volume (``None`` without a volume)."""
        return None if self.volume is None else self.mass / self.volume

    def principal(self) -> tuple[np.ndarray, np.ndarray]:
        """Principal moments and axes, from a symmetric eigendecomposition of the inertia.

        Returns:
            ``moments`` ``(3,)`` [kg·m²] in ascending order, and ``axes`` ``(3, 3)``: a proper
            rotation (det +1) whose columns are the principal axes in the shape's axes, so that
            ``axes.T @ inertia @ axes`` is ``diag(moments)``. Equal moments (a sphere, a cube)
            leave their axes free: any orthonormal choice is returned.
        """
        moments, axes = _eigen(np.asarray(self.inertia))
        if np.linalg.det(axes) < 0.0:
            axes[:, 2] = -axes[:, 2]
        return moments, axes

    def about(self, point: Any) -> np.ndarray:
        """Inertia tensor ``(3, 3)`` [kg·m²] about ``point`` ``(3,)`` [m] (shape's coordinates),
        in the shape's axes: J = I + m (|d|² E − d dᵀ), d = point − centre of mass."""
        d = _vector("point", point, "m") - self.center_of_mass
        return self.inertia + self.mass * (float(d @ d) * np.eye(3) - np.outer(d, d))

    def translated(self, offset: Any) -> MassProperties:
        """The properties of the shape moved by ``offset`` ``(3,)`` [m]: the centre of mass moves
        with it; the inertia about it does not change."""
        moved = self.center_of_mass + _vector("offset", offset, "m")
        return MassProperties(self.mass, moved, self.inertia, self.volume)

    def rotated(self, rotation: Any) -> MassProperties:
        """The properties of the shape turned by ``rotation`` (a proper 3 × 3 rotation matrix)
        about the origin of its coordinates: centre of mass R c, inertia R I Rᵀ."""
        matrix = _rotation(rotation)
        inertia = matrix @ self.inertia @ matrix.T
        return MassProperties(
            self.mass, matrix @ self.center_of_mass, 0.5 * (inertia + inertia.T), self.volume
        )
