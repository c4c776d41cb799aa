"""The ``system`` entity kind: a named mechanical system in generalized coordinates."""

from ..kind import EntityKind
from .schema import System

KIND = EntityKind(
    name="system",
    schema=System,
    summary="a named mechanical system in generalized coordinates",
    build=f"{__name__}.build",
    state=True,
)
