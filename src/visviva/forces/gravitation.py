"""Newtonian gravitation among particles, as a force of the pipeline.

The particles it targets attract one another with the direct or Barnes–Hut method of
:mod:`visviva.mechanics.gravity` (the one implementation; Plummer softening ``ε``):

    F_i = G m_i Σ_{j≠i} m_j (x_j − x_i) / (|x_j − x_i|² + ε²)^{3/2}        [N]
    U   = −G Σ_{i<j} m_i m_j / (|x_j − x_i|² + ε²)^{1/2}                    [J]

Its Jacobian is dense (every body pulls every other), so it gives none: implicit methods on a
scene with gravitation solve matrix-free (Newton–Krylov), and the stability advisor estimates
its spectrum from force differences (:mod:`visviva.analysis.advisor`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from .._validation import real_number
from ..mechanics.gravity import (
    PointMasses,
    accelerations_into,
    check_masses,
    check_method,
    potential_energy,
)
from .base import Targets

if TYPE_CHECKING:
    from ..ode.workspace import Workspace

__all__ = ["Gravitation"]


class Gravitation:
    """Mutual gravitation of a set of particles.

    Args:
        mass: Particle masses [kg], shape ``(N,)`` (zero: a test particle that feels the others
            but pulls none).
        targets: The particles that attract one another (default: all).
        G: The constant of gravitation [m³/(kg s²)].
        softening: Plummer softening ``ε`` [m], at least 0.
        method: ``"direct"`` (every pair, exact) or ``"barnes_hut"`` (a tree, ``O(N log N)``).
        theta: Barnes–Hut opening angle in (0, 1].
    """

    conservative: ClassVar[bool] = True
    velocity_dependent: ClassVar[bool] = False
    linear_damping: ClassVar[bool] = False
    #: No compiled form: a scene with gravitation takes the generic road.
    compiled: ClassVar[None] = None

    def __init__(
        self,
        mass: np.ndarray,
        targets: Targets | None = None,
        *,
        G: float,
        softening: float = 0.0,
        method: str = "direct",
        theta: float = 0.5,
    ) -> None:
        self.targets = targets or Targets(len(mass))
        self.masses = check_masses(np.asarray(mass)[self.targets.indices], len(self.targets))
        self.G = real_number("G", G, positive=True, unit=" m³/(kg s²)")
        self.softening = real_number("softening", softening, nonnegative=True, unit=" m")
        self.method, self.theta = check_method(method, theta)

    def _bodies(self, x: np.ndarray) -> PointMasses:
        return PointMasses(x[self.targets.indices], self.masses, self.softening)

    def accumulate(
        self, t: float, x: np.ndarray, v: np.ndarray, out: np.ndarray, work: Workspace | None = None
    ) -> None:
        """Add ``m_i a_i`` [N] to ``out`` for every target.

        Raises:
            ModelError: If two bodies coincide and there is no softening.
        """

        def scratch() -> np.ndarray:
            return np.empty((len(self.targets), 3))

        into = scratch() if work is None else work.get(self, scratch)
        accelerations = accelerations_into(self._bodies(x), self.G, self.method, self.theta, into)
        out[self.targets.indices] += self.masses[:, None] * accelerations

    def potential(self, t: float, x: np.ndarray, alive: np.ndarray | None = None) -> float:
        """``U`` [J] of the targets (they are never born or killed: see the model's checks)."""
        return potential_energy(self._bodies(x), self.G, self.method, self.theta)

    def jacobian_blocks(self) -> None:
        """None: the Jacobian is dense (see the module docstring)."""
        return None

    def add_jacobian(self, t, x, v, dfdx, dfdv, form="exact") -> None:  # type: ignore[no-untyped-def]
        """Never called: there is no analytic Jacobian."""
        raise NotImplementedError("gravitation has no analytic Jacobian")
