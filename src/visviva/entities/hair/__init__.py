"""The ``hair`` entity kind: a hair strand: edge, bending and torsion springs along a curve."""

from ..kind import EntityKind
from .schema import Hair, HairMethods

__all__ = ["KIND", "HairMethods"]

KIND = EntityKind(
    name="hair",
    schema=Hair,
    summary="a hair strand: edge, bending and torsion springs along a curve",
    build=f"{__name__}.build",
    holds_particles=True,
)
