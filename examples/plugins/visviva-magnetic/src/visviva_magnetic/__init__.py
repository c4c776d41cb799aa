"""A visviva plugin: a uniform magnetic field acting on charged particles.

The Lorentz force of a field ``B`` [T] on a particle of charge ``q`` [C] moving at ``v`` [m/s]
is ``F = q v × B`` [N]: always across the velocity, it does no work, and a particle moving
across a uniform field circles it at the cyclotron frequency ``ω = |q| B / m`` on a circle of
radius ``r = m v⊥ / (|q| B)`` (J. D. Jackson, *Classical Electrodynamics*, 3rd ed., §12.2).

This package shows the plugin API of ``docs/extending.md``: the table of the kind's
parameters (a pydantic model), the force (the :class:`visviva.forces.Force` protocol, with its
exact Jacobian), and :func:`visviva.entities.force_kind`, which makes the kind; the entry point
in ``pyproject.toml`` registers it with visviva when the package is installed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, ClassVar, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from visviva.entities import force_kind
from visviva.forces import Targets

if TYPE_CHECKING:
    from visviva.entities import BuildContext
    from visviva.forces.base import JacobianForm
    from visviva.ode import Workspace

__all__ = ["KIND", "MagneticField", "MagneticFieldTable"]

Finite = Annotated[float, Field(strict=True, allow_inf_nan=False)]


class MagneticFieldTable(BaseModel):
    """``type = "magnetic_field"``: a uniform field ``field`` [T] on the particles of
    ``targets`` (every particle by default), each of charge ``charge`` [C]."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    type: Literal["magnetic_field"]
    name: str | None = None
    field: tuple[Finite, Finite, Finite] = Field(description="the field B [T]")
    charge: Finite = Field(description="the charge q of each targeted particle [C]")
    targets: list[str] | None = Field(None, description="entity names (default: every particle)")


class MagneticField:
    """The Lorentz force ``q v × B`` on the targets (see the module docstring).

    Args:
        field: ``B`` [T], ``(3,)``.
        charge: ``q`` [C] of each target.
        targets: The particles it acts on.
    """

    #: Not the gradient of a potential (it depends on the velocity), though it does no work.
    conservative: ClassVar[bool] = False
    velocity_dependent: ClassVar[bool] = True
    #: Its ``∂F/∂v = −q [B]×`` is skew-symmetric, not a damper's symmetric matrix.
    linear_damping: ClassVar[bool] = False
    #: No compiled form: the fused particle step leaves a scene with it to the generic road.
    compiled: ClassVar[None] = None

    def __init__(self, field: np.ndarray, charge: float, targets: Targets) -> None:
        self.field = np.asarray(field, dtype=np.float64)
        self.charge = float(charge)
        self.targets = targets
        b = self.field
        # [B]× with [B]× v = B × v; then v × B = −[B]× v.
        self._cross = np.array([[0.0, -b[2], b[1]], [b[2], 0.0, -b[0]], [-b[1], b[0], 0.0]])

    def accumulate(
        self, t: float, x: np.ndarray, v: np.ndarray, out: np.ndarray, work: Workspace | None = None
    ) -> None:
        """Add ``q v × B`` [N] to ``out`` ``(N, 3)`` for every target."""
        index = self.targets.indices
        out[index] += self.charge * np.cross(v[index], self.field)

    def potential(self, t: float, x: np.ndarray, alive: np.ndarray | None = None) -> float:
        """0: a magnetic field does no work (the kinetic energy is the whole energy)."""
        return 0.0

    def jacobian_blocks(self) -> tuple[np.ndarray, np.ndarray]:
        """One 3×3 block per target, on the diagonal."""
        return self.targets.indices, self.targets.indices

    def add_jacobian(
        self,
        t: float,
        x: np.ndarray,
        v: np.ndarray,
        dfdx: np.ndarray,
        dfdv: np.ndarray,
        form: JacobianForm = "exact",
    ) -> None:
        """``∂F/∂x = 0``, ``∂F/∂v = −q [B]×`` on each block (every form: nothing to drop)."""
        dfdv -= self.charge * self._cross


def _make(entity: MagneticFieldTable, context: BuildContext) -> MagneticField:
    return MagneticField(np.array(entity.field), entity.charge, context.targets(entity.targets))


KIND = force_kind(
    "magnetic_field",
    MagneticFieldTable,
    MagneticField,
    _make,
    summary="a uniform magnetic field on charged particles (the Lorentz force q v × B)",
)
