"""The value types every part of the scene description shares (the entity kinds' tables and
:mod:`visviva.model.scene`): strict numbers that must be finite, vectors, names, colours, and
the base of every table.

Strict means a value of the wrong type is refused rather than converted (``dt = "0.005"`` is
an error); an integer is accepted where a real number belongs.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

__all__ = [
    "MAX_PARTICLES",
    "Color",
    "Count",
    "Finite",
    "Fraction",
    "Index",
    "Name",
    "Names",
    "NonNegative",
    "Positive",
    "Seed",
    "Strict",
    "Vector",
]

#: Most particles one scene may create: 50 million is ~2.4 GB of state; more is a typo.
MAX_PARTICLES = 50_000_000

Finite = Annotated[float, Field(strict=True, allow_inf_nan=False)]
Positive = Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)]
NonNegative = Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)]
Vector = tuple[Finite, Finite, Finite]
Name = Annotated[str, Field(strict=True, min_length=1, max_length=200, pattern=r"^[^\x00-\x1f]*$")]
Fraction = Annotated[float, Field(strict=True, ge=0, le=1, allow_inf_nan=False)]
Color = tuple[Fraction, Fraction, Fraction]
#: The index of one of an entity's points (no entity holds more than MAX_PARTICLES).
Index = Annotated[int, Field(strict=True, ge=0, lt=MAX_PARTICLES)]
#: A number of particles.
Count = Annotated[int, Field(strict=True, ge=1, le=MAX_PARTICLES)]
#: A random seed.
Seed = Annotated[int, Field(strict=True, ge=0, lt=2**63)]
#: The names of entities (a force's, collider's or behaviour's targets).
Names = Annotated[list[Name], Field(min_length=1)]


class Strict(BaseModel):
    """A table of the scene: unknown keys are errors, numbers finite, the value frozen."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
