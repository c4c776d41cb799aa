"""The force protocol every particle force follows.

Positions and velocities are structure-of-arrays ``(N, 3)`` float64 arrays [m], [m/s] in the
world frame (Y up). A force *adds* its contribution to ``out`` (so the model sums all forces into
one array without temporaries) and reports its potential energy, so that every run can monitor
the total energy. Forces that depend on velocity (drag, dampers) have no potential; they return
0 and declare ``conservative = False``.
"""

from __future__ import annotations

from typing import ClassVar, Protocol

import numpy as np

__all__ = ["Force"]


class Force(Protocol):
    """What the model needs from a force on particles."""

    #: True if the force is ``−∇U`` of the energy it reports (energy is then conserved).
    conservative: ClassVar[bool]

    def accumulate(self, t: float, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        """Add the force [N] on every particle to ``out``, shape ``(N, 3)``."""
        ...

    def potential(self, t: float, x: np.ndarray) -> np.ndarray:
        """Potential energy [J]: one value, or one per system for a batch ``(B, N, 3)``."""
        ...
