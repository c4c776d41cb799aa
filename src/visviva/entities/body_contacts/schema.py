"""The scene entity of rigid-body contacts (``type = "body_contacts"``).

One such entity makes the bodies it targets (the body entities it names, or every body)
collide with each other and with the scene's impulse colliders (planes, boxes and spheres),
each body as its collision shape (``collision_shape``, ``convex_pieces`` of the body entity),
with impulses of restitution and Coulomb friction and resting contact that holds stacks; the
stage that does it, its method and sources are in :mod:`visviva.collision.body_contacts`. A
scene holds at most one.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated, Literal

from pydantic import Field

from ..fields import Fraction, Name, Names, NonNegative, Positive, Strict
from ..methods import Builds, given

__all__ = ["BodyContactSettings"]


class BodyContactSettings(Strict):
    """``type = "body_contacts"``: the targeted bodies collide with each other and with the
    impulse colliders that target them."""

    type: Literal["body_contacts"]
    name: Name | None = None
    targets: Names | None = Field(None, description="body entity names (default: every body)")
    restitution: Fraction | None = Field(
        None, description="one e for every pair (default: each pair's larger)"
    )
    friction: NonNegative | None = Field(
        None, description="one μ for every pair (default: each pair's √(μ_a μ_b))"
    )
    iterations: Annotated[int, Field(strict=True, ge=1, le=10_000)] = Field(
        20, description="sweeps of impulses, then of overlap corrections, per step"
    )
    resting_speed: NonNegative | None = Field(
        None, description="approach speed below which a contact rests [m/s] (default: 2|g|dt)"
    )
    time_of_impact: Literal["advancement", "bisection"] = Field(
        "advancement",
        description="how a fast body's first impact in a step is found: conservative "
        "advancement (sees a body pass through a thin one) or seed 003's bisection",
    )
    particles: Names | None = Field(
        None,
        description="particle entities whose particles collide with the bodies (default: none)",
    )
    particle_restitution: Fraction = Field(
        0.5, description="e of the particles' contacts with bodies (a pair takes the larger)"
    )
    particle_friction: NonNegative = Field(
        0.5, description="μ of the particles' contacts with bodies (a pair takes √(μ_p μ_b))"
    )
    response: Literal["impulses", "penalty"] = Field(
        "impulses",
        description="impulses (rest, restitution, friction; the default) or penalty springs "
        "at the overlapping contact points (seeds 000 and 002)",
    )
    stiffness: Positive | None = Field(
        None, description="penalty: k per contact point [N/m] (required with penalty)"
    )
    damping: NonNegative | None = Field(
        None,
        description="penalty: c per contact point [N·s/m] (default: 2√(k m) for the lightest "
        "body, critical)",
    )
    impacts: Literal["sequential", "simultaneous"] = Field(
        "sequential",
        description="sequential (bounces among the resting contacts' impulses) or "
        "simultaneous (generalized reflections: an impact travels along a row)",
    )


class BodyContactMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_body_contacts(
        self: Builds,
        *,
        targets: Sequence[str] | None = None,
        restitution: float | None = None,
        friction: float | None = None,
        iterations: int | None = None,
        resting_speed: float | None = None,
        impacts: str | None = None,
        time_of_impact: str | None = None,
        particles: Sequence[str] | None = None,
        particle_restitution: float | None = None,
        particle_friction: float | None = None,
        response: str | None = None,
        stiffness: float | None = None,
        damping: float | None = None,
        name: str | None = None,
    ) -> int:
        """Make the bodies of ``targets`` (default: every body) collide with each other and
        with the impulse colliders that target them, each as its collision shape; a pair's
        restitution and friction are the bodies' own (the larger e, √(μ_a μ_b)) unless
        ``restitution`` or ``friction`` is given for all; ``iterations`` sweeps per step;
        approaches slower than ``resting_speed`` [m/s] rest; ``impacts="simultaneous"``
        resolves a step's impacts together by generalized reflections, as a Newton's cradle
        needs; a fast body's first impact within a step is found by ``time_of_impact``
        ``"advancement"`` or ``"bisection"`` (:mod:`visviva.collision.impact_time`); the
        particles of the entities ``particles`` collide with the bodies too, as spheres of
        their radii with ``particle_restitution`` and ``particle_friction``.
        ``response="penalty"`` replaces the impulses by springs of ``stiffness`` k [N/m] and
        ``damping`` c [N·s/m] at each overlapping contact point, with Coulomb friction
        (:mod:`visviva.collision.body_penalty`)."""
        return self.add("body_contacts", **given(locals()))
