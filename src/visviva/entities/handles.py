"""The ``handle`` table of a deformable body: its pinned points follow a prescribed rigid
motion (a moving head, a hand dragging a rope) instead of staying where they are.

Every body takes one (``[entities.handle]`` under its ``[[entities]]`` table, or ``handle=``
in its ``SceneBuilder.add_*``); it moves all of the body's ``pinned`` points. The motion, its
clock and how every integrator holds the points on it are described in
:mod:`visviva.particles.handles`.
"""

from __future__ import annotations

from typing import Self

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from .fields import Finite, NonNegative, Positive, Strict, Vector

__all__ = ["Handle"]


class Handle(Strict):
    """``handle``: the body's pinned points move rigidly — translated at ``velocity`` and
    turned about ``axis`` through ``pivot`` (which travels with them) by ``angular_velocity``
    and an oscillation of ``amplitude`` at ``frequency`` — on a clock that starts at
    ``start``, takes ``ramp`` seconds to speed up and to slow down, and stops at ``stop``.

    Example: a head that turns by 1.2 rad about the vertical through its centre between
    t = 1 s and t = 2 s, speeding up and slowing down over 0.25 s, is ``pivot = [0, 1.5, 0]``,
    ``angular_velocity = 1.6`` (1.2 rad over the 0.75 s the clock gains), ``start = 1``,
    ``stop = 2``, ``ramp = 0.25``.
    """

    pivot: Vector | None = Field(
        None,
        description="the point the turn is about, at t = 0 [m] (default: the pinned points' "
        "centroid)",
    )
    velocity: Vector = Field((0.0, 0.0, 0.0), description="velocity of the translation [m/s]")
    axis: Vector = Field((0.0, 1.0, 0.0), description="axis of the turn (any length but 0)")
    angular_velocity: Finite = Field(
        0.0, description="rate of the turn [rad/s], right-handed about the axis"
    )
    amplitude: Finite = Field(
        0.0, description="amplitude of an oscillating turn, A sin(2π f s) [rad]"
    )
    frequency: NonNegative = Field(0.0, description="frequency of the oscillation [Hz]")
    start: NonNegative = Field(0.0, description="when the motion starts [s]")
    stop: Positive | None = Field(None, description="when it stops [s] (default: never)")
    ramp: NonNegative = Field(
        0.0, description="time to speed up after start and to slow down before stop [s]"
    )

    @property
    def turns(self) -> bool:
        """True if the motion has a turn (a steady one or an oscillation)."""
        return self.angular_velocity != 0.0 or self.amplitude != 0.0

    @model_validator(mode="after")
    def _consistent(self) -> Self:
        if self.stop is not None and self.stop <= self.start:
            raise PydanticCustomError(
                "stop_before_start",
                "`stop` ({stop} s) must be after `start` ({start} s)",
                {"stop": self.stop, "start": self.start},
            )
        if self.stop is not None and 2.0 * self.ramp > self.stop - self.start:
            raise PydanticCustomError(
                "ramp_too_long",
                "`ramp` ({ramp} s) must fit twice between `start` and `stop` ({span} s): the "
                "handle speeds up over one ramp and slows down over another; shorten the ramp "
                "or move `stop`",
                {"ramp": self.ramp, "span": self.stop - self.start},
            )
        if self.amplitude != 0.0 and self.frequency == 0.0:
            raise PydanticCustomError(
                "oscillation_without_frequency",
                "an oscillation of `amplitude` {amplitude} rad needs a `frequency` > 0 [Hz]",
                {"amplitude": self.amplitude},
            )
        if self.frequency != 0.0 and self.amplitude == 0.0:
            raise PydanticCustomError(
                "oscillation_without_amplitude",
                "`frequency` {frequency} Hz moves nothing without an `amplitude` [rad]: give "
                "one, or drop the frequency",
                {"frequency": self.frequency},
            )
        if self.turns and not any(self.axis):
            raise PydanticCustomError(
                "zero_axis",
                "`axis` is the zero vector: give the direction to turn about, e.g. [0, 1, 0]",
            )
        return self
