"""The ``crowd`` entity kind: pedestrians walking with the social-force model, through exits."""

from ..kind import EntityKind
from .schema import Crowd, CrowdMethods

__all__ = ["KIND", "CrowdMethods"]

KIND = EntityKind(
    name="crowd",
    schema=Crowd,
    summary="pedestrians walking with the social-force model, through exits",
    build=f"{__name__}.build",
)
