"""The ``cloth`` entity kind: a cloth grid with structural, shear and bending springs."""

from ..kind import EntityKind
from .schema import RENAMED, Cloth, ClothMethods

__all__ = ["KIND", "ClothMethods"]

KIND = EntityKind(
    name="cloth",
    schema=Cloth,
    summary="a cloth grid with structural, shear and bending springs",
    build=f"{__name__}.build",
    holds_particles=True,
    renamed=RENAMED,
)
