"""The scene entity of a flock (``type = "boids"``), as plain data validated by pydantic.

A flock is a behaviour, not a body: it names the particle entities whose particles are its
boids (``targets``, e.g. a ``particle_cloud``) and steers them after every step with Reynolds'
rules (:mod:`visviva.particles.boids` has the model, its units and its sources). Each field
is checked here on its own and against its neighbours (``separation ≤ radius``,
``min_speed ≤ max_speed``, a weight only with what it weighs); :mod:`.build` checks the names
(targets and ``leader`` exist, the leader is not a target, no particle entity is in two
flocks).
"""

from __future__ import annotations

from collections.abc import Sequence
from types import MappingProxyType
from typing import Annotated, Literal, Self

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from ..fields import Name, Names, NonNegative, Positive, Strict, Vector
from ..methods import Builds, Triple, given, refusing_renamed

__all__ = ["Boids"]

Degrees = Annotated[float, Field(strict=True, gt=0, le=360, allow_inf_nan=False)]

#: Field names this kind gave up, and their replacements (issue 26, one vocabulary).
RENAMED = MappingProxyType({"fov": "fov_deg", "max_force": "max_acceleration"})


class Boids(Strict):
    """``type = "boids"``: Reynolds' flocking of the particles of ``targets``."""

    type: Literal["boids"]
    name: Name | None = None
    targets: Names = Field(description="particle entities whose particles are the boids")
    radius: Positive = Field(description="how far a boid sees its flockmates [m]")
    separation: Positive = Field(description="flockmates closer than this push away [m]")
    fov_deg: Degrees = Field(
        360.0, description="field of view, full angle around the heading [degrees]"
    )
    max_speed: Positive = Field(description="desired and largest speed [m/s]")
    min_speed: NonNegative = Field(0.0, description="least speed of a moving boid [m/s]")
    max_acceleration: Positive = Field(description="bound of the steering acceleration [m/s^2]")
    separation_weight: NonNegative = Field(1.5, description="weight of separation [1/s]")
    alignment_weight: NonNegative = Field(1.0, description="weight of alignment [1/s]")
    cohesion_weight: NonNegative = Field(1.0, description="weight of cohesion [1/s]")
    goal: Vector | None = Field(None, description="a point the flock seeks [m]")
    goal_weight: NonNegative | None = Field(None, description="weight of the goal [1/s] (1)")
    leader: Name | None = Field(None, description="a particle entity the boids follow")
    leader_weight: NonNegative | None = Field(None, description="weight of the leader [1/s] (1)")
    look_ahead: Positive | None = Field(
        None, description="distance from a collider at which boids turn away [m] (2 V^2/A)"
    )
    min_distance: Positive | None = Field(
        None,
        description="no two boids are left closer than this after a step [m], at most "
        "`separation` (default: separation only steers)",
    )
    plane: Literal["xz"] | None = Field(None, description='"xz": a 2-D flock (default 3-D)')

    @model_validator(mode="after")
    def _consistent(self) -> Self:
        if self.separation > self.radius:
            raise PydanticCustomError(
                "separation_radius",
                "`separation` ({separation} m) must not exceed `radius` ({radius} m): a boid "
                "pushes away only flockmates it sees",
                {"separation": self.separation, "radius": self.radius},
            )
        if self.min_distance is not None and self.min_distance > self.separation:
            raise PydanticCustomError(
                "min_distance",
                "`min_distance` ({low} m) must not exceed `separation` ({high} m): separation "
                "steers boids apart before they are held apart",
                {"low": self.min_distance, "high": self.separation},
            )
        if self.min_speed > self.max_speed:
            raise PydanticCustomError(
                "min_speed",
                "`min_speed` ({low} m/s) must not exceed `max_speed` ({high} m/s)",
                {"low": self.min_speed, "high": self.max_speed},
            )
        for weight, what in (("goal_weight", "goal"), ("leader_weight", "leader")):
            if getattr(self, weight) is not None and getattr(self, what) is None:
                raise PydanticCustomError(
                    "weight_without",
                    "`{weight}` is given without `{what}`: give the {what} too, or leave the "
                    "weight out",
                    {"weight": weight, "what": what},
                )
        return self


class BoidsMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    @refusing_renamed("boids", RENAMED)
    def add_boids(
        self: Builds,
        targets: Sequence[str],
        *,
        radius: float,
        separation: float,
        max_speed: float,
        max_acceleration: float,
        fov_deg: float | None = None,
        min_speed: float | None = None,
        separation_weight: float | None = None,
        alignment_weight: float | None = None,
        cohesion_weight: float | None = None,
        goal: Triple | None = None,
        goal_weight: float | None = None,
        leader: str | None = None,
        leader_weight: float | None = None,
        look_ahead: float | None = None,
        min_distance: float | None = None,
        plane: str | None = None,
        name: str | None = None,
    ) -> int:
        """Add a flock: Reynolds' boids steering the particles of the entities named in
        ``targets`` (:mod:`visviva.particles.boids`). Boids see flockmates within ``radius``
        [m] and the field of view ``fov_deg`` [degrees]; separation from those closer than
        ``separation`` [m], alignment and cohesion with weights [1/s]; desired speed
        ``max_speed`` [m/s], steering bounded by ``max_acceleration`` [m/s²]; an optional ``goal``
        point and ``leader`` entity (weights default to 1/s); colliders avoided from
        ``look_ahead`` [m]; no two boids left closer than ``min_distance`` [m] if given;
        ``plane="xz"`` for a 2-D flock."""
        return self.add("boids", **given(locals()))
