"""The ``soft_lattice`` entity kind: a volumetric soft body on a lattice of springs."""

from ..kind import EntityKind
from .schema import RENAMED, SoftLattice, SoftLatticeMethods

__all__ = ["KIND", "SoftLatticeMethods"]

KIND = EntityKind(
    name="soft_lattice",
    schema=SoftLattice,
    summary="a volumetric soft body on a lattice of springs",
    build=f"{__name__}.build",
    holds_particles=True,
    renamed=RENAMED,
)
