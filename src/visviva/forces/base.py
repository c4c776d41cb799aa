"""The force protocol every particle force follows, and the pieces forces share.

Positions and velocities are structure-of-arrays ``(N, 3)`` float64 arrays [m], [m/s] in the
world frame (Y up), ``N`` the particle capacity of the scene. A force:

* *adds* its contribution [N] to ``out`` (so the model sums every force into one array without
  temporaries), on the particles it targets, keeping any scratch arrays in the run's
  :class:`~visviva.ode.workspace.Workspace` (a force is part of a shared model: it never
  changes after it is built);
* reports its potential energy [J] (0 for forces that have none: drag, wind, vortices), so
  every run can monitor the total energy; ``conservative`` says whether the force is ``−∇U``;
* declares its compiled form (``compiled``: a field's law, springs' arrays, or ``None``), from
  which the fused particle step evaluates it with the same compiled laws as ``accumulate``;
* gives its exact Jacobians ``∂F/∂x`` and ``∂F/∂v`` as 3×3 blocks on a sparsity pattern fixed
  when the force is built (``jacobian_blocks``), which implicit methods and the stability
  advisor assemble into one sparse matrix (:mod:`visviva.forces.assembly`). A force without an
  analytic Jacobian (n-body gravitation, whose Jacobian is dense) says so with
  ``jacobian_blocks() is None``; implicit methods then go matrix-free.

The kernels here are serial Numba loops over the targets: a run whose every piece is compiled
takes the fused, parallel particle step instead (:mod:`visviva.particles.fused`), and the rest
pays Python's overhead per force per step, which threads would only add to.

Every Jacobian is tested against finite differences of the same force, and every conservative
force's ``F = −∇U`` the same way (``tests/test_forces.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar, Literal, Protocol

import numpy as np

if TYPE_CHECKING:
    from ..ode.workspace import Workspace
    from .laws import FieldLaw
    from .springs import SpringSet

__all__ = ["Force", "JacobianForm", "Targets", "diagonal_blocks"]


#: Which Jacobian a force adds: ``"exact"``; ``"symmetric"``, ``∂F/∂x`` without the parts
#: that are not ``−∇²U`` (a damper's change of direction with the positions), the Hessian of
#: backward Euler's incremental potential; ``"definite"``, that made positive semi-definite
#: too (a compressed spring's negative stiffness across it dropped, Choi & Ko 2002), so that
#: Newton's matrix ``M − h D − h² K`` is positive definite.
JacobianForm = Literal["exact", "symmetric", "definite"]


class Force(Protocol):
    """What the model needs from a force on particles."""

    #: True if the force is ``−∇U`` of the energy it reports (energy is then conserved).
    conservative: ClassVar[bool]
    #: True if the force depends on the velocities.
    velocity_dependent: ClassVar[bool]

    @property
    def compiled(self) -> FieldLaw | SpringSet | None:
        """Its compiled form, from which the fused particle step evaluates it: a field's law
        and parameters (:class:`~.laws.FieldLaw`), springs' arrays
        (:class:`~.springs.SpringSet`), or ``None`` — a scene with such a force takes the
        generic road."""
        ...

    @property
    def linear_damping(self) -> bool:
        """True if the force is ``−∇U + D v`` with ``D = ∂F/∂v`` symmetric and independent of
        ``v`` (a linear damper): with such forces only, backward Euler's step minimizes an
        incremental potential (:class:`~visviva.forces.ForceSum`'s ``gradient_form``)."""
        ...

    def accumulate(
        self, t: float, x: np.ndarray, v: np.ndarray, out: np.ndarray, work: Workspace | None = None
    ) -> None:
        """Add the force [N] on every targeted particle to ``out``, shape ``(N, 3)``.

        ``work`` is the run's storage, where a force that needs scratch arrays keeps them
        (``None``: a call on its own, which makes fresh ones). A force holds nothing that
        changes: many runs of one model evaluate it at once."""
        ...

    def potential(self, t: float, x: np.ndarray, alive: np.ndarray | None = None) -> float:
        """Potential energy [J] of the targeted particles (those ``alive``, if given)."""
        ...

    def jacobian_blocks(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Particle indices ``(rows, cols)`` of the 3×3 blocks ``∂F_row/∂x_col`` and
        ``∂F_row/∂v_col`` this force may fill, fixed for the force's life; ``None`` if it has
        no analytic Jacobian."""
        ...

    def add_jacobian(
        self,
        t: float,
        x: np.ndarray,
        v: np.ndarray,
        dfdx: np.ndarray,
        dfdv: np.ndarray,
        form: JacobianForm = "exact",
    ) -> None:
        """Add ``∂F/∂x`` [N/m] and ``∂F/∂v`` [N·s/m] into ``dfdx`` and ``dfdv``, each
        ``(blocks, 3, 3)`` in the order of :meth:`jacobian_blocks`: the exact Jacobians, or
        the forms implicit steps ask for (:data:`JacobianForm`; a force whose Jacobian has
        no part to drop adds its exact one for every form)."""
        ...


class Targets:
    """The particles a force acts on: every particle, or a sorted set of indices.

    Args:
        count: Number of particles ``N`` in the scene.
        indices: Indices of the targeted particles, or ``None`` for all of them.

    Attributes:
        indices: Sorted unique ``int64`` indices, shape ``(n,)`` (``arange(N)`` for all).
        everything: True if every particle is targeted.
    """

    def __init__(self, count: int, indices: Any = None) -> None:
        if indices is None:
            self.indices = np.arange(count, dtype=np.int64)
        else:
            self.indices = np.unique(np.asarray(indices, dtype=np.int64))
        self.everything = self.indices.shape[0] == count
        self.indices.flags.writeable = False

    def __len__(self) -> int:
        return int(self.indices.shape[0])

    def mask(self, alive: np.ndarray | None) -> np.ndarray:
        """The targeted indices of the particles that are alive."""
        if alive is None:
            return self.indices
        return self.indices[alive[self.indices]]


def diagonal_blocks(targets: Targets) -> tuple[np.ndarray, np.ndarray]:
    """The pattern of a force on each particle from its own state: blocks ``(i, i)``."""
    return targets.indices, targets.indices
