"""The ``emitter`` entity kind: particles born over time from a shape, living their lifetimes."""

from ..kind import EntityKind
from .schema import RENAMED, Emitter, EmitterMethods

__all__ = ["KIND", "EmitterMethods"]

KIND = EntityKind(
    name="emitter",
    schema=Emitter,
    summary="particles born over time from a shape, living their lifetimes",
    build=f"{__name__}.build",
    holds_particles=True,
    renamed=RENAMED,
)
