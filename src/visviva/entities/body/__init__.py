"""The ``body`` entity kind: a rigid body: a shape with its mass properties, state (x, q, P, L)."""

from ..kind import EntityKind
from .schema import RENAMED, RigidBody, RigidBodyMethods

__all__ = ["KIND", "RigidBodyMethods"]

KIND = EntityKind(
    name="body",
    schema=RigidBody,
    summary="a rigid body: a shape with its mass properties, state (x, q, P, L)",
    build=f"{__name__}.build",
    state=True,
    renamed=RENAMED,
)
