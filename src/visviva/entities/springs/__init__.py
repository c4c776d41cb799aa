"""The ``springs`` entity kind: particles joined by damped springs on any graph."""

from ..kind import EntityKind
from .schema import SpringGraph, SpringGraphMethods

__all__ = ["KIND", "SpringGraphMethods"]

KIND = EntityKind(
    name="springs",
    schema=SpringGraph,
    summary="particles joined by damped springs on any graph",
    build=f"{__name__}.build",
    holds_particles=True,
)
