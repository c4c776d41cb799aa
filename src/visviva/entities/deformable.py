"""What every deformable body shares: particles joined by damped springs, each entity a spring
topology of :mod:`visviva.deformables`.

Curves: ``rope`` (seed 002) and ``hair`` (Selle, Lentine & Fedkiw 2008). Sheets: ``cloth`` (a
grid, Choi & Ko 2002) and ``cloth_mesh`` (any triangle mesh). Solids: ``soft_lattice`` (a
lattice, seed 004) and ``soft_mesh`` (any tetrahedral mesh). Any graph: ``springs``. Every
body's particles enter the state in the order of its points (or vertices), its ``pinned``
points stay where they are — or, with a ``handle`` (:mod:`.handles`), follow its prescribed
motion — and every spring rests at its length as built (a ``springs`` entity may give its own
rest lengths).

The schema checks each field (types, signs, finite numbers) and the pins; what only the
geometry can tell — points that coincide, a triangle without area, a tetrahedron turned inside
out, an index past the points — is refused when the body is built, at the field and item at
fault (``entities[2].triangles[7]``). The build shared by every kind of body is in
:mod:`.deformable_build`.

References:
    K.-J. Choi, H.-S. Ko, "Stable but responsive cloth", SIGGRAPH 2002.
    A. Selle, M. Lentine, R. Fedkiw, "A mass spring model for hair simulation", SIGGRAPH 2008.
"""

from __future__ import annotations

from typing import Annotated, ClassVar, Self

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from .fields import Index, Positive, Strict
from .handles import Handle

__all__ = ["DeformableBody", "FilePath", "Pins", "PositiveEach", "check_pins"]

#: Indices of the points held fixed.
Pins = list[Index]
#: A file's path (relative: to the scene file's folder, or the working directory).
FilePath = Annotated[
    str, Field(strict=True, min_length=1, max_length=4096, pattern=r"^[^\x00-\x1f]*$")
]
#: One value, or one per point (or per spring).
PositiveEach = Positive | Annotated[list[Positive], Field(min_length=1)]


def check_pins(pinned: list[int], count: int, body: str) -> None:
    """Refuse a pinned index past the body's ``count`` points."""
    outside = [i for i in pinned if i >= count]
    if outside:
        raise PydanticCustomError(
            "pin_out_of_range",
            "pinned index {index} is not a point of this {body} (it has {count}: 0 to {last})",
            {"index": outside[0], "body": body, "count": count, "last": count - 1},
        )


class DeformableBody(Strict):
    """What every deformable body's schema shares: its pins must be among its points, and a
    handle moves its pins."""

    #: The body's name in messages.
    noun: ClassVar[str]
    pinned: Pins
    handle: Handle | None = Field(
        None, description="a prescribed rigid motion of the pinned points (default: they stay)"
    )

    @property
    def point_count(self) -> int:
        """The body's particles."""
        raise NotImplementedError

    @model_validator(mode="after")
    def _pins_on_the_body(self) -> Self:
        if self.point_count is not None:  # a mesh file's pins are checked once it is read
            check_pins(self.pinned, self.point_count, self.noun)
        if self.handle is not None and not self.pinned:
            raise PydanticCustomError(
                "handle_without_pins",
                "a handle moves the pinned points, and this {body} has none: list the points "
                "it should move in `pinned`",
                {"body": self.noun},
            )
        return self
