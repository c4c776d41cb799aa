"""One step of the pipeline: integrate the smooth dynamics, apply the stages, watch the result.

Every run — ``vv.solve`` on a problem, ``visviva run`` on a scene, a user's
:class:`~visviva.simulation.Simulation` stepped from Python — advances its state through
:meth:`Stepper.step`:

1. the integrator advances the integrated parts by ``h`` (:meth:`Integrator.step`);
2. the post-step stages, in order, may change the state discontinuously (collisions with
   colliders, births and deaths of particles; later constraint projection and pins);
3. the divergence watch checks the result and stops a blown-up run with an explanation.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, ClassVar, Protocol

from ..errors import SimulationError

if TYPE_CHECKING:
    from ..integrators import Integrator
    from ..ode.state import State
    from ..ode.system import System
    from .watch import DivergenceWatch

__all__ = ["FusedStep", "Stage", "Stepper"]


class Stage(Protocol):
    """What the loop needs from a post-step stage.

    A stage receives the state before and after the integrator's step (the one before lets
    it find when, within the step, something happened: a time of impact, a birth) and returns
    the state to keep. It must not modify either state's arrays in place.
    """

    #: True if the stage has a compiled form, so that a run made only of compiled pieces may
    #: still take its whole-run compiled path.
    compiled: ClassVar[bool]

    def apply(self, before: State, after: State, h: float) -> State:
        """The state to keep after a step of ``h`` [s] from ``before`` to ``after``."""
        ...


class FusedStep(Protocol):
    """A whole step — integrator, stages and the watch's check — in one compiled pass, for
    models whose every piece has a compiled form (:mod:`visviva.particles.fused`)."""

    def step(self, state: State, h: float, t_after: float, limit: float) -> tuple[State, bool]:
        """The state after a step of ``h`` ending at ``t_after``, and whether it may be beyond
        the divergence ``limit`` (checked then by the watch)."""
        ...


class Stepper:
    """Advances states step by step: integrator, then stages, then the watch.

    Args:
        system: The system the integrator evaluates.
        integrator: The time integrator.
        watch: The divergence watch.
        stages: Post-step stages, applied in order.
        fused: A compiled whole step that takes the place of the integrator and the stages
            (it must compute what they would).
    """

    def __init__(
        self,
        system: System,
        integrator: Integrator,
        watch: DivergenceWatch,
        stages: Sequence[Stage] = (),
        fused: FusedStep | None = None,
    ) -> None:
        self.system = system
        self.integrator = integrator
        self.watch = watch
        self.stages = tuple(stages)
        self.fused = fused

    def step(self, state: State, h: float, t_after: float, index: int) -> State:
        """The state after one step of ``h`` [s] ending at ``t_after`` (from the caller's
        integer counter); ``index`` numbers the step in the run, for messages.

        Raises:
            SimulationDiverged: If the new state is not finite or beyond the watch's limit.
            SimulationError: If the integrator failed (its ``step`` is set to ``index``).
        """
        if self.fused is not None:
            after, suspect = self.fused.step(state, h, t_after, self.watch.limit)
            self.system.counters.f_evaluations += 1
            self.system.counters.accepted_steps += 1
            if suspect and not self.watch.healthy(after):
                raise self.watch.diverged(after, index, state)
            return after
        try:
            after = self.integrator.step(self.system, state, h).at_time(t_after)
        except SimulationError as failure:
            failure.step = index
            raise
        for stage in self.stages:
            after = stage.apply(state, after, h)
        self.system.counters.accepted_steps += 1
        if not self.watch.healthy(after):
            raise self.watch.diverged(after, index, state)
        return after
