"""The ``body_contacts`` entity kind: rigid bodies that collide with each other and with the
scene's colliders."""

from ..kind import EntityKind
from .schema import BodyContactMethods, BodyContactSettings

__all__ = ["KIND", "BodyContactMethods"]

KIND = EntityKind(
    name="body_contacts",
    schema=BodyContactSettings,
    summary="rigid bodies colliding with each other and with colliders",
    build=f"{__name__}.build",
)
