"""The ``system`` entity kind: a named mechanical system in generalized coordinates."""

from ..kind import EntityKind
from .schema import System, SystemMethods

__all__ = ["KIND", "SystemMethods"]

KIND = EntityKind(
    name="system",
    schema=System,
    summary="a named mechanical system in generalized coordinates",
    build=f"{__name__}.build",
    state=True,
)
