"""Forces on particles: each adds its contribution to a force array, reports its energy and
gives its Jacobians (see :mod:`visviva.forces.base` for the protocol)."""

from .assembly import ForceSum
from .base import Force, Targets
from .fields import Attractor, Damping, Drag, QuadraticDrag, UniformGravity, Vortex
from .gravitation import Gravitation
from .springs import Springs

__all__ = [
    "Attractor",
    "Damping",
    "Drag",
    "Force",
    "ForceSum",
    "Gravitation",
    "QuadraticDrag",
    "Springs",
    "Targets",
    "UniformGravity",
    "Vortex",
]
