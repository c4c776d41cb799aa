"""The ``force`` entity kind: a force field on particles, or gravitation among them."""

from ..kind import EntityKind
from .schema import ForceField, ForceFieldMethods

__all__ = ["KIND", "ForceFieldMethods"]

KIND = EntityKind(
    name="force",
    schema=ForceField,
    summary="a force field on particles, or gravitation among them",
    build=f"{__name__}.build",
)
