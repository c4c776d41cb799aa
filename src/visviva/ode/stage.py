"""The post-step stage: what may change a state between two integrator steps, and what it says
of itself.

The integrator advances the smooth dynamics; then the model's stages, in the order of their
:class:`Phase`, may change the state discontinuously — steer a flock, put held particles back on
their handles, resolve collisions, give birth and kill. A stage declares everything the pipeline
needs to know about it as class attributes, so nothing is probed: whether it has a compiled
form the fused steps take its place with, whether it changes the energy (a scene whose stages
do not is conservative, and its energy measures the integrator's error), whether it removes
particles (the recordings then keep who is alive), and the parts it carries in the state.
"""

from __future__ import annotations

from enum import IntEnum
from typing import TYPE_CHECKING, ClassVar, Protocol

if TYPE_CHECKING:
    import numpy as np

    from .state import State
    from .workspace import Workspace

__all__ = ["Phase", "Stage"]


class Phase(IntEnum):
    """When in a step a stage runs; stages of one phase run by their ``order``, then in the
    order they were built."""

    #: Behaviours steer from the state the integrator reached (boids, crowds).
    BEHAVIOURS = 0
    #: Constraints put the state back on them: handles, unit quaternions.
    CONSTRAINTS = 1
    #: Contacts are found and resolved on the constrained state.
    CONTACTS = 2
    #: Births and deaths come last: a particle born in a step starts from its end.
    EMISSION = 3


class Stage(Protocol):
    """What the pipeline needs from a post-step stage.

    A stage receives the state before and after the integrator's step (the one before lets it
    find when, within the step, something happened: a time of impact, a birth) and returns the
    state to keep. It must not change either state's arrays in place, nor itself: a stage is
    part of a shared model, and keeps what it needs between calls (neighbour grids, scratch
    arrays) in the run's :class:`~visviva.ode.workspace.Workspace`, and what a checkpoint must
    restore (warm starts, exit times) in the state's carried parts.
    """

    #: When in a step it runs.
    phase: ClassVar[Phase]
    #: Its place among the stages of its phase (lower first).
    order: ClassVar[int]
    #: True if the fused compiled steps know how to take its place.
    compiled: ClassVar[bool]
    #: True if it may change the energy (every stage but a projection that keeps it).
    changes_energy: ClassVar[bool]
    #: True if it may remove particles (exits, lifetimes).
    kills_particles: ClassVar[bool]

    def carried_start(self) -> dict[str, np.ndarray]:
        """The parts it carries in the state, as they are at the start (empty if none)."""
        ...

    def apply(self, before: State, after: State, h: float, work: Workspace) -> State:
        """The state to keep after a step of ``h`` [s] from ``before`` to ``after``; ``work``
        is the run's storage."""
        ...
