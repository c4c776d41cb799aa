"""Forces on particles: each adds its contribution to a force array and knows its energy."""

from .base import Force
from .gravity import UniformGravity

__all__ = ["Force", "UniformGravity"]
