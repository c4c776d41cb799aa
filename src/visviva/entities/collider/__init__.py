"""The ``collider`` entity kind: a static shape that particles bounce off or are pushed out of."""

from ..kind import EntityKind
from .schema import Collider, ColliderMethods

__all__ = ["KIND", "ColliderMethods"]

KIND = EntityKind(
    name="collider",
    schema=Collider,
    summary="a static shape that particles bounce off or are pushed out of",
    build=f"{__name__}.build",
)
