"""The ``rope`` entity kind: particles joined in order by damped springs."""

from ..kind import EntityKind
from .schema import Rope, RopeMethods

__all__ = ["KIND", "RopeMethods"]

KIND = EntityKind(
    name="rope",
    schema=Rope,
    summary="particles joined in order by damped springs",
    build=f"{__name__}.build",
    holds_particles=True,
)
