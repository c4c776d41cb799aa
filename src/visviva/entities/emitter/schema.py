"""The scene table of an emitter of particles that live and die (``type = "emitter"``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Annotated, Any, Literal, get_args

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from ..fields import (
    Color,
    Count,
    Fraction,
    Name,
    NonNegative,
    Positive,
    Seed,
    Strict,
    Vector,
)
from ..methods import Builds, Triple, given, refusing_renamed

__all__ = ["EMITTER_SHAPES", "Burst", "Emitter"]

#: Field names this kind gave up, and their replacements (issue 26, one vocabulary).
RENAMED = MappingProxyType({"spread": "spread_deg"})


#: A value drawn for each particle: one number, or ``[low, high]`` for a uniform draw.
NonNegativeRange = NonNegative | tuple[NonNegative, NonNegative]


PositiveRange = Positive | tuple[Positive, Positive]


EmitterShape = Literal["point", "disc", "sphere", "box", "mesh"]


EMITTER_SHAPES: tuple[str, ...] = get_args(EmitterShape)


def _ordered_range(value: float | tuple[float, float], name: str) -> None:
    if isinstance(value, tuple) and value[0] > value[1]:
        raise PydanticCustomError(
            "range_order",
            "`{name}` is a range [low, high] with low > high (got {value})",
            {"name": name, "value": list(value)},
        )


def _ramp_order(stops: list[tuple[float, ...]] | None, name: str) -> None:
    if stops is None:
        return
    ages = [stop[0] for stop in stops]
    if ages != sorted(ages):
        raise PydanticCustomError(
            "ramp_order",
            "the stops of `{name}` must be in increasing order of age fraction (got {ages})",
            {"name": name, "ages": ages},
        )


class Burst(Strict):
    """A burst: ``count`` particles born at once at ``time``."""

    time: NonNegative = Field(description="when [s]")
    count: Count = Field(description="how many particles")


class Emitter(Strict):
    """``type = "emitter"``: particles born over time from a shape, each living for its lifetime.

    Particles are born at ``rate`` per second between ``start`` and ``stop`` (the fractional
    remainder carried from step to step, so a rate of 0.5 per step gives one particle every
    other step) and in ``bursts``; each gets a speed along a direction in a cone, a lifetime, a
    radius and a colour, drawn from seeded random numbers, and ramps of colour and size over its
    life. The model keeps ``capacity`` slots for them (by default enough for every particle that
    can be alive at once).
    """

    type: Literal["emitter"]
    name: Name | None = None
    rate: NonNegative = Field(0.0, description="particles born per second [1/s]")
    start: NonNegative = Field(0.0, description="when continuous emission starts [s]")
    stop: Positive | None = Field(None, description="when it stops [s] (default: never)")
    bursts: list[Burst] = Field(default_factory=list, description="particles born at once")
    shape: EmitterShape = Field("point", description="where particles are born")
    position: Vector = Field((0.0, 0.0, 0.0), description="centre of the shape [m]")
    radius: NonNegative = Field(0.0, description="radius of a disc or sphere [m]")
    extent: tuple[Positive, Positive, Positive] = Field(
        (1.0, 1.0, 1.0), description="edge lengths of a box [m]"
    )
    normal: Vector = Field((0.0, 1.0, 0.0), description="normal of a disc")
    surface: bool = Field(False, description="born on the surface of a sphere or box")
    vertices: list[Vector] | None = Field(None, description="mesh vertices [m]")
    triangles: list[tuple[int, int, int]] | None = Field(None, description="mesh triangles")
    direction: Vector = Field((0.0, 1.0, 0.0), description="axis of the emission cone")
    spread_deg: Annotated[float, Field(strict=True, ge=0, le=180, allow_inf_nan=False)] = Field(
        0.0, description="half-angle of the emission cone [degrees]"
    )
    speed: NonNegativeRange = Field(1.0, description="initial speed [m/s] or [low, high]")
    lifetime: PositiveRange = Field(1.0, description="lifetime [s] or [low, high]")
    particle_radius: PositiveRange = Field(0.02, description="radius [m] or [low, high]")
    particle_mass: Positive = Field(0.001, description="mass of each particle [kg]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")
    color_ramp: (
        Annotated[list[tuple[Fraction, Fraction, Fraction, Fraction]], Field(min_length=1)] | None
    ) = Field(None, description="[[age fraction, r, g, b], ...]: colour over each particle's life")
    size_ramp: Annotated[list[tuple[Fraction, NonNegative]], Field(min_length=1)] | None = Field(
        None, description="[[age fraction, scale], ...]: radius factor over each particle's life"
    )
    capacity: Count | None = Field(None, description="particle slots (default: enough)")
    seed: Seed = Field(0, description="random seed")

    @model_validator(mode="after")
    def _consistent(self) -> Emitter:
        for name in ("speed", "lifetime", "particle_radius"):
            _ordered_range(getattr(self, name), name)
        _ramp_order(self.color_ramp, "color_ramp")
        _ramp_order(self.size_ramp, "size_ramp")
        if self.rate == 0.0 and not self.bursts:
            raise PydanticCustomError(
                "emits_nothing", "this emitter emits nothing: give `rate` > 0 or `bursts`"
            )
        if self.stop is not None and self.stop <= self.start:
            raise PydanticCustomError(
                "stop_before_start",
                "`stop` ({stop} s) must be after `start` ({start} s)",
                {"stop": self.stop, "start": self.start},
            )
        for name in ("direction", "normal"):
            if not any(getattr(self, name)):
                raise PydanticCustomError(
                    "zero_vector", "`{name}` must not be the zero vector", {"name": name}
                )
        if (self.shape == "mesh") != (self.vertices is not None or self.triangles is not None):
            raise PydanticCustomError(
                "mesh_fields",
                '`vertices` and `triangles` belong to (and are needed by) shape = "mesh"',
            )
        if self.shape == "mesh" and (self.vertices is None or self.triangles is None):
            raise PydanticCustomError(
                "mesh_fields", 'shape = "mesh" needs both `vertices` and `triangles`'
            )
        return self


class EmitterMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    @refusing_renamed("emitter", RENAMED)
    def add_emitter(
        self: Builds,
        *,
        rate: float | None = None,
        start: float | None = None,
        stop: float | None = None,
        bursts: Sequence[Mapping[str, float]] | None = None,
        shape: str | None = None,
        position: Triple | None = None,
        radius: float | None = None,
        extent: Triple | None = None,
        normal: Triple | None = None,
        surface: bool | None = None,
        vertices: Any = None,
        triangles: Any = None,
        direction: Triple | None = None,
        spread_deg: float | None = None,
        speed: float | Sequence[float] | None = None,
        lifetime: float | Sequence[float] | None = None,
        particle_radius: float | Sequence[float] | None = None,
        particle_mass: float | None = None,
        color: Triple | None = None,
        color_ramp: Sequence[Sequence[float]] | None = None,
        size_ramp: Sequence[Sequence[float]] | None = None,
        capacity: int | None = None,
        seed: int | None = None,
        name: str | None = None,
    ) -> int:
        """Add an emitter (see :class:`visviva.model.scene.Emitter` for every field): particles
        born at ``rate`` [1/s] and in ``bursts`` (``{"time": s, "count": n}``) from a ``shape``
        (point, disc, sphere, box, mesh), flying out along ``direction`` within ``spread_deg``
        [degrees] at ``speed`` [m/s], living ``lifetime`` [s]; ranges are ``[low, high]``."""
        return self.add("emitter", **given(locals()))
