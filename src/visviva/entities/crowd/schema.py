"""The scene entity of a crowd (``type = "crowd"``), as plain data validated by pydantic.

A crowd is a behaviour of particles, like a force: its ``targets`` name the ``particles`` or
``particle_cloud`` entities whose particles are its agents (their masses and radii are the
agents'). The agents walk in the horizontal XZ plane to the crowd's ``goal``, or to the nearest
of its ``exits``, with the social-force model of Helbing & Molnár (1995) and Helbing, Farkas &
Vicsek (2000) (:mod:`visviva.particles.crowd`); the defaults are the 2000 paper's values and the
1995 paper's mean walking speed. The crowd's ``walls`` name collider entities (default: every
collider of the scene). An agent that enters one of the ``exits`` (axis-aligned boxes) leaves
the scene::

    [[entities]]
    type = "crowd"
    targets = ["people"]
    preferred_speed = 1.34
    exits = [{ center = [6.5, 1.0, 0.0], size = [1.0, 2.0, 3.0] }]
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Annotated, Any, Literal

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from ..fields import Name, NonNegative, Positive, Strict, Vector
from ..methods import Builds, Triple, given

__all__ = ["Crowd", "Exit", "wall_indices"]

Names = Annotated[list[Name], Field(min_length=1)]


class Exit(Strict):
    """An exit: an axis-aligned box that removes the agents entering it."""

    center: Vector = Field(description="centre of the box [m]")
    size: tuple[Positive, Positive, Positive] = Field(
        description="edge lengths along x, y and z [m] (y must span the agents' heights)"
    )


class Crowd(Strict):
    """``type = "crowd"``: the targeted particles walk as pedestrians (social-force model)."""

    type: Literal["crowd"]
    name: Name | None = None
    targets: Names = Field(description="the particles or particle_cloud entities that walk")
    goal: Vector | None = Field(
        None, description="where the agents walk to [m] (default: the nearest exit's centre)"
    )
    exits: list[Exit] = Field(default_factory=list, description="boxes the agents leave by")
    walls: Names | None = Field(
        None, description="collider entities that are walls (default: every collider)"
    )
    preferred_speed: Positive = Field(1.34, description="preferred walking speed v0 [m/s]")
    relaxation_time: Positive = Field(0.5, description="relaxation time tau [s]")
    max_speed: Positive | None = Field(
        None, description="largest speed [m/s] (default: 1.3 preferred_speed)"
    )
    repulsion: NonNegative = Field(2000.0, description="repulsion strength A [N]")
    repulsion_range: Positive = Field(0.08, description="repulsion range B [m]")
    body_stiffness: NonNegative = Field(1.2e5, description="body force k [kg/s^2]")
    friction: NonNegative = Field(2.4e5, description="sliding friction kappa [kg/(m s)]")

    @model_validator(mode="after")
    def _consistent(self) -> Crowd:
        if self.goal is None and not self.exits:
            raise PydanticCustomError(
                "no_goal", "a crowd needs a `goal` or at least one of `exits` to walk to"
            )
        if self.max_speed is not None and self.max_speed < self.preferred_speed:
            raise PydanticCustomError(
                "max_speed",
                "`max_speed` ({top} m/s) must be at least `preferred_speed` ({speed} m/s)",
                {"top": self.max_speed, "speed": self.preferred_speed},
            )
        return self

    @property
    def top_speed(self) -> float:
        """``max_speed``, or its default 1.3 ``preferred_speed`` (Helbing & Molnár 1995)."""
        return 1.3 * self.preferred_speed if self.max_speed is None else self.max_speed


def wall_indices(crowd: Crowd, entities: Sequence[Any]) -> list[int]:
    """The entity indices of a crowd's walls: the colliders its ``walls`` name (an entity's
    name is its own or its type and index, as in :func:`~visviva.model.build.entity_names`),
    or every collider."""
    colliders = [(i, e) for i, e in enumerate(entities) if e.type == "collider"]
    if crowd.walls is None:
        return [i for i, _ in colliders]
    return [i for i, e in colliders if (e.name or f"{e.type}{i}") in crowd.walls]


class CrowdMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_crowd(
        self: Builds,
        targets: Sequence[str],
        *,
        goal: Triple | None = None,
        exits: Sequence[Mapping[str, Triple]] | None = None,
        walls: Sequence[str] | None = None,
        preferred_speed: float | None = None,
        relaxation_time: float | None = None,
        max_speed: float | None = None,
        repulsion: float | None = None,
        repulsion_range: float | None = None,
        body_stiffness: float | None = None,
        friction: float | None = None,
        name: str | None = None,
    ) -> int:
        """Add a crowd: the particles of ``targets`` walk in the XZ plane to ``goal`` [m] or
        the nearest of ``exits`` (``{"center": [x, y, z], "size": [sx, sy, sz]}`` boxes that
        remove who enters), avoiding each other and the colliders named in ``walls`` (default:
        all) with the social-force model (:mod:`visviva.particles.crowd`): ``preferred_speed``
        v0 [m/s], ``relaxation_time`` tau [s], ``max_speed`` [m/s], ``repulsion`` A [N] of
        range ``repulsion_range`` B [m], ``body_stiffness`` k [kg/s²], ``friction`` kappa
        [kg/(m·s)]; defaults from Helbing, Farkas & Vicsek (2000)."""
        return self.add("crowd", **given(locals()))
