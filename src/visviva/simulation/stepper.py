"""One step of the pipeline: integrate the smooth dynamics, apply the stages, watch the result.

Every run — ``vv.solve`` on a problem, ``visviva run`` on a scene, a user's
:class:`~visviva.simulation.Simulation` stepped from Python — advances its state through
:meth:`Stepper.step`:

1. the integrator advances the integrated parts by ``h`` (:meth:`Integrator.step`);
2. the post-step stages (:class:`~visviva.ode.stage.Stage`), in the order of their phases, may
   change the state discontinuously (behaviours, constraints, contacts, births and deaths);
3. the divergence watch checks the result and stops a blown-up run with an explanation.

A :class:`FusedStep` may take the place of 1 and 2 (the particle scenes' one-pass step). It
works in place, on its own copy of the state (the states it returns are brought up to date by
:meth:`Stepper.settled`), so the stepper keeps a journal to give back an earlier state after a
failure: a copy of the state at most :data:`JOURNAL_STEPS` steps old and the steps taken since,
replayed bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ..errors import SimulationError
from ..ode.state import State

if TYPE_CHECKING:
    from ..integrators import Integrator
    from ..ode.stage import Stage
    from ..ode.system import System
    from .watch import DivergenceWatch

__all__ = ["JOURNAL_STEPS", "FusedStep", "Stepper"]

#: Steps between the copies of the state a fused step's journal keeps (copying costs about a
#: step; a failure replays at most this many steps).
JOURNAL_STEPS = 256


class FusedStep(Protocol):
    """A whole step — integrator, stages and the watch's check — in one compiled pass, for
    models whose every piece has a compiled form (:mod:`visviva.particles.fused`).

    It may work in place on a copy of its own: the state it is given is spent, and the state
    it returns has up-to-date arrays only once passed through :meth:`settled`.
    """

    def step(self, state: State, h: float, t_after: float, limit: float) -> tuple[State, bool]:
        """The state after a step of ``h`` ending at ``t_after``, and whether it may be beyond
        the divergence ``limit`` (checked then by the watch)."""
        ...

    def settled(self, state: State) -> State:
        """``state`` with its arrays up to date."""
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
        # The fused step's journal: a copy of an earlier state, the (h, t_after) of every step
        # since, and the latest state stepped to.
        self._origin: State | None = None
        self._journal: list[tuple[float, float]] = []
        self._latest: State | None = None

    def step(
        self, state: State, h: float, t_after: float, index: int, boundary: bool = True
    ) -> State:
        """The state after one step of ``h`` [s] ending at ``t_after`` (from the caller's
        integer counter); ``index`` numbers the step in the run, for messages; ``boundary``
        is False for the substeps after a step's first (the journal's copies are of states
        the caller may ask back).

        With a fused step, ``state`` is spent and the result needs :meth:`settled`.

        Raises:
            SimulationDiverged: If the new state is not finite or beyond the watch's limit.
            SimulationError: If the integrator failed (its ``step`` is set to ``index``).
        """
        if self.fused is not None:
            return self._fused_step(state, h, t_after, index, boundary)
        try:
            after = self.integrator.step(self.system, state, h).at_time(t_after)
        except SimulationError as failure:
            failure.step = index
            raise
        for stage in self.stages:
            after = stage.apply(state, after, h, self.system.workspace)
        self.system.counters.accepted_steps += 1
        if not self.watch.healthy(after):
            raise self.watch.diverged(after, index, state)
        return after

    def settled(self, state: State) -> State:
        """``state`` with its arrays up to date (see :class:`FusedStep`)."""
        return state if self.fused is None else self.fused.settled(state)

    def earlier(self, state: State, steps: int) -> State:
        """``state``, from which the latest ``steps`` steps were taken, as it was then: itself,
        unless a fused step has since changed it in place; then the journal replays it."""
        if self.fused is None:
            return state
        return self._replay(len(self._journal) - steps)

    def _fused_step(
        self, state: State, h: float, t_after: float, index: int, boundary: bool
    ) -> State:
        assert self.fused is not None
        if state is not self._latest or (boundary and len(self._journal) >= JOURNAL_STEPS):
            self._origin = _copy(self.fused.settled(state), self._origin)
            self._journal = []
        after, suspect = self.fused.step(state, h, t_after, self.watch.limit)
        self._journal.append((h, t_after))
        self._latest = after
        self.system.counters.f_evaluations += 1
        self.system.counters.accepted_steps += 1
        if suspect and not self.watch.healthy(self.fused.settled(after)):
            raise self.watch.diverged(after, index, self.earlier(after, 1))
        return after

    def _replay(self, steps: int) -> State:
        """The state ``steps`` journal steps after the journal's copy (taken again)."""
        assert self.fused is not None and self._origin is not None
        if not 0 <= steps <= len(self._journal):
            raise ValueError(f"the journal holds {len(self._journal)} steps, not {steps}")
        state = _copy(self._origin)
        for h, t_after in self._journal[:steps]:
            state, _ = self.fused.step(state, h, t_after, math.inf)
        self._latest = None  # the next step starts a new journal
        return self.fused.settled(state)


def _copy(state: State, into: State | None = None) -> State:
    """``state`` with copies of its arrays (into the arrays of ``into`` if they fit: a fresh
    array costs a page fault per 4 KiB on first write, several times the copy itself)."""
    if into is None or _shapes(into) != _shapes(state):
        parts = tuple(np.array(part) for part in state.parts)
        return State(
            state.t, parts, state.layout, {k: np.array(v) for k, v in state.carried.items()}
        )
    for target, part in zip(into.parts, state.parts, strict=True):
        np.copyto(target, part)
    for name, value in state.carried.items():
        np.copyto(into.carried[name], value)
    return State(state.t, into.parts, state.layout, into.carried)


def _shapes(state: State) -> tuple[list[tuple[int, ...]], dict[str, tuple[int, ...]]]:
    return [p.shape for p in state.parts], {k: v.shape for k, v in state.carried.items()}
