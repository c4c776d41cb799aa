"""Ensembles: many runs of one model's equations advancing side by side in one batched state.

A sweep over initial conditions — a thousand double pendulums released from a thousand angles —
runs the same equations a thousand times. When every model of such an ensemble is a single
named system (no particles, bodies or stages) and their systems share their compiled equations
(:func:`~visviva.ode.stacking.equations_key`: same parameters, only the start differs), the
members are stacked into one batched problem (:func:`~visviva.ode.stacking.stack`) and stepped
through the one loop (:func:`~visviva.simulation.loop.advance`): one evaluation of the equations
per stage for the whole batch instead of one per member, and no process per member.

Each member computes exactly what its own run (:class:`~visviva.simulation.Simulation` of its
model) computes, bit for bit: the same explicit or symplectic method, step schedule, recorded
frames and energy, with the batch's row ``i`` evaluated by member ``i``'s function. (Implicit
methods do not batch: their Newton iterations would run until every member converged.)

The divergence watch uses the smallest of the members' limits; a member that fails (diverges,
or takes the batch down with a failure that names no member) is taken out of the batch, which
goes on from its last good state without it, and is reported so that the caller runs it alone,
where it fails exactly as it would have (with its own limit and message).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ModelError, SimulationDiverged, SimulationError
from ..integrators import get
from ..ode.stacking import equations_key, stack
from ..ode.state import State
from .loop import Schedule, advance
from .progress import Progress
from .recorder import FrameRecorder
from .stepper import Stepper
from .watch import DivergenceWatch

if TYPE_CHECKING:
    from ..model import Model

__all__ = ["EnsembleFrame", "EnsembleRun", "ensemble_key", "run_ensemble"]

#: ``on_frame(state, energy, members)``: a recorded frame of the batch — its state (row ``r``
#: is member ``members[r]``, an index into the models given), each row's energy ``(rows,)`` or
#: ``None`` — at the times each member's own run records; the arrays belong to the run.
EnsembleFrame = Callable[[State, "np.ndarray | None", Sequence[int]], None]


def ensemble_key(model: Model) -> Hashable | None:
    """What models must share to advance in one batch, or ``None`` if ``model`` cannot join
    one: it holds anything but a single named system, that system's problem cannot be stacked,
    or its method is implicit (Newton's iterations run until every member of a batch has
    converged, so a member would take other iterations than alone). The key compares equal
    only within one process (it holds the functions)."""
    if model.particle_count or model.body_count or model.stages or len(model.systems) != 1:
        return None
    if get(model.integration.method).implicit:
        return None
    equations = equations_key(model.systems[0].problem)
    if equations is None:
        return None
    settings = model.integration
    return (equations, settings.method, settings.dt, settings.substeps, settings.record_every)


@dataclass
class EnsembleRun:
    """What :func:`run_ensemble` did.

    Attributes:
        counters: The work of the batch (``accepted_steps``, ``f_evaluations``, ...): a call on
            the whole batch counts once, so each member's count is what its own run counts.
        wall_time_s: Time of the whole batch [s].
        failed: Members taken out of the batch, by index, with why: run them alone.
    """

    counters: dict[str, int] = field(default_factory=dict)
    wall_time_s: float = 0.0
    failed: dict[int, str] = field(default_factory=dict)


def run_ensemble(
    models: Sequence[Model],
    until: float,
    *,
    on_frame: EnsembleFrame | None = None,
    progress: bool | None = False,
) -> EnsembleRun:
    """Run every model of an ensemble from its start to ``until`` [s] in one batch.

    Args:
        models: Models with one :func:`ensemble_key` (checked).
        until: End time [s], as for :meth:`Simulation.run <visviva.simulation.Simulation.run>`.
        on_frame: Called with each recorded frame of the batch (the start, every
            ``record_every``-th step and the last; see :data:`EnsembleFrame`). A member that
            fails has had its frames up to the failure passed: discard them.
        progress: Show a progress bar over the batch's steps.

    Returns:
        The shared work counters and the members that failed (see the module docstring).

    Raises:
        ModelError: Models that do not share one key, or an end before their start.
        Interrupted: On SIGINT/SIGTERM (inside
            :class:`~visviva.simulation.interrupt.StopOnSignal`), after the current step; the
            frames up to it were passed to ``on_frame``.
    """
    if not models:
        raise ModelError("`models` is empty: an ensemble needs at least one model")
    key = ensemble_key(models[0])
    if key is None or any(ensemble_key(m) != key for m in models[1:]):
        raise ModelError(
            "these models cannot advance in one batch: each must be one named system, all "
            "with the same equations (only initial conditions may differ) and the same "
            "integration settings"
        )
    starts = [m.initial_state() for m in models]
    settings = models[0].integration
    origin = starts[0].t
    if until < origin:
        raise ModelError(f"`until` ({until!r} s) is before the start {origin!r} s")
    integrator = get(settings.method)
    problem = stack([m.systems[0].problem for m in models], name=models[0].name)
    system = problem.system()
    integrator.check(system)
    members = list(range(len(models)))  # batch row -> member index
    state = problem.initial_state().at_time(origin)
    result = EnsembleRun()
    started = time.perf_counter()

    def record(frame: State, energy: Any) -> None:
        if on_frame is not None:
            on_frame(frame, energy, members)

    schedule = Schedule.build(origin, until, settings.dt, settings.substeps)
    with Progress(schedule.steps, f"{integrator.name} x{len(models)}", progress) as bar:
        recorder = FrameRecorder(system, state, on_frame=record, keep=False)
        done = 0  # steps of dt taken from the origin
        while members and done < schedule.steps:
            # The smallest limit of the members still in: a member stopped by it that its own
            # limit would have let through runs alone, where its own limit applies.
            limit = min(DivergenceWatch.default_limit(starts[m]) for m in members)
            watch = DivergenceWatch(system, integrator, settings.dt, state, limit)
            stepper = _Rewinding(system, integrator, watch)
            piece = Schedule.build(origin, until, settings.dt, settings.substeps, done)
            try:
                advance(stepper, state, piece, settings.record_every, recorder, bar)
                done = schedule.steps
            except SimulationError as failure:
                rows = _failed_rows(failure, len(members))
                for row in rows:
                    result.failed[members[row]] = str(failure)
                keep = [row for row in range(len(members)) if row not in rows]
                members = [members[row] for row in keep]
                state = _rows(failure.state, keep)
                done += failure.steps_done
                recorder = FrameRecorder(system, state, include=False, on_frame=record, keep=False)
    result.counters = system.counters.as_dict()
    result.wall_time_s = time.perf_counter() - started
    return result


class _Rewinding(Stepper):
    """A stepper whose failed step leaves no work in the counters: the batch takes that step
    again without the member that failed it, and each member counts what it counts alone."""

    def step(
        self, state: State, h: float, t_after: float, index: int, boundary: bool = True
    ) -> State:
        counters = self.system.counters
        before = counters.as_dict()
        try:
            return super().step(state, h, t_after, index, boundary)
        except SimulationError:
            for name, value in before.items():
                setattr(counters, name, value)
            raise


def _failed_rows(failure: SimulationError, count: int) -> list[int]:
    """The batch rows a failure is about: the diverged one, or every row if it names none."""
    row = failure.system if isinstance(failure, SimulationDiverged) else None
    return list(range(count)) if row is None else [row]


def _rows(state: State, keep: list[int]) -> State:
    """``state`` with only the batch rows ``keep`` (its derivative too, so that a method that
    reuses it takes the very steps it would have taken)."""
    parts = tuple(part[keep] for part in state.parts)
    derivative = None if state.derivative is None else tuple(d[keep] for d in state.derivative)
    return State(state.t, parts, state.layout, state.carried, derivative)
