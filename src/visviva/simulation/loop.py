"""The one fixed-step simulation loop every model runs through.

:func:`run_fixed_steps` (the fixed-step road of :func:`~visviva.simulation.solve`) advances a
problem from ``t0`` to ``until`` in steps of ``dt``, each made of ``substeps`` integrator steps
of ``h = dt/substeps``; :class:`~visviva.simulation.Simulation` runs a scene through the same
:func:`advance`. Time is never accumulated: step ``n`` ends at ``t0 + (n + 1)·dt`` and its
substep ``j`` at ``t0 + n·dt + (j + 1)·h``, computed from integer counters, so a million steps
land on the same times as one would by hand (``t += dt`` drifts by ``~n·ε``). If
``until − t0`` is not a whole number of steps, the last step is shortened to end exactly at
``until``.

Every ``record_every``-th step (and the last) becomes a frame of the :class:`Recording`. After
every integrator step the divergence watch checks the state; a blow-up stops the run with
:class:`~visviva.errors.SimulationDiverged`, whose ``recording`` attribute holds the frames
recorded before it. Inside :class:`~visviva.simulation.interrupt.StopOnSignal`, a Ctrl-C or
SIGTERM ends the run after the current step (compiled: after the current chunk of frames): that
state becomes the last frame and :class:`~visviva.simulation.interrupt.Interrupted` carries the
recording to the caller.

When the problem's functions are Numba functions and the method has a compiled step, the whole
loop runs compiled (:mod:`visviva.integrators.compiled`) with the same schedule, frames and
watch; ``compiled=False`` forces the NumPy path.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import real_number, whole_number
from .._version import __version__
from ..errors import ModelError, SimulationError
from ..integrators import Integrator, get
from ..model.model import MAX_STEPS
from .interrupt import Interrupted, stop_requested
from .progress import Progress
from .recorder import FrameCallback, FrameRecorder, FrameSink
from .recording import Recording
from .stepper import Stepper
from .watch import DivergenceWatch

if TYPE_CHECKING:
    from ..integrators.base import CompiledStep
    from ..ode.problems import Problem
    from ..ode.state import State
    from ..ode.system import System

__all__ = ["Schedule", "advance", "run_fixed_steps"]

#: System-steps per compiled chunk: large enough to hide the call overhead, small enough for the
#: progress bar to move and the frame buffer to stay small.
CHUNK_SYSTEM_STEPS = 200_000


@dataclass(frozen=True)
class Schedule:
    """When each step happens: ``full_steps`` steps of ``dt``, then possibly one shorter step.

    Time is counted on the grid ``t0 + n·dt`` (substeps at ``+ j·h`` within a step, ``h =
    dt/substeps``) from ``t0``, the grid's origin; a run that continues an earlier one on the
    same grid starts at step ``first``, so its times are exactly those one longer run would
    have had.

    Attributes:
        t0: The grid's origin [s].
        until: End time [s].
        dt: Step [s].
        substeps: Integrator steps per step.
        first: Steps of ``dt`` already taken from ``t0`` before this run.
        full_steps: Number of steps of exactly ``dt`` in this run.
        last_dt: Length of the final shortened step [s], or 0 if ``until`` is on the grid.
    """

    t0: float
    until: float
    dt: float
    substeps: int
    full_steps: int
    last_dt: float
    first: int = 0

    @classmethod
    def build(cls, t0: float, until: float, dt: float, substeps: int, first: int = 0) -> Schedule:
        """Plan the steps from ``t0 + first·dt`` to ``until`` on the grid of origin ``t0`` (a
        remainder below 1e-9 steps is rounding)."""
        ratio = (until - t0) / dt
        nearest = round(ratio)
        if nearest >= first + 1 and abs(ratio - nearest) <= 1e-9 * max(1.0, ratio):
            return cls(t0, until, dt, substeps, int(nearest) - first, 0.0, first)
        full = max(math.floor(ratio), first)
        return cls(t0, until, dt, substeps, full - first, (until - t0) - full * dt, first)

    @property
    def steps(self) -> int:
        """Number of steps, the shortened one included."""
        return self.full_steps + (1 if self.last_dt > 0.0 else 0)

    @property
    def h(self) -> float:
        """Integrator step of the full steps [s]."""
        return self.dt / self.substeps

    def substep(self, step: int, sub: int) -> tuple[float, float]:
        """``(h, t_after)`` of substep ``sub`` of this run's step ``step`` (time from integer
        counters)."""
        if step < self.full_steps:
            n = self.first + step  # steps of dt before this one, from the grid's origin
            if sub + 1 < self.substeps:
                return self.h, self.t0 + n * self.dt + (sub + 1) * self.h
            # A step ends on the grid of dt whatever its substeps: a run split into pieces
            # passes through the same times as one long run.
            last = step + 1 == self.steps
            return self.h, self.until if last else self.t0 + (n + 1) * self.dt
        h_last = self.last_dt / self.substeps
        if sub + 1 == self.substeps:
            return h_last, self.until
        start = self.t0 + (self.first + self.full_steps) * self.substeps * self.h
        return h_last, start + (sub + 1) * h_last


def run_fixed_steps(
    problem: Problem,
    method: str | Integrator = "rk4",
    *,
    dt: float,
    until: float,
    substeps: int = 1,
    record_every: int = 1,
    progress: bool | None = None,
    divergence_limit: float | None = None,
    compiled: bool | None = None,
    on_frame: FrameCallback | None = None,
) -> Recording:
    """Run ``problem`` with fixed steps and return the recorded frames: the fixed-step road
    of :func:`~visviva.simulation.solve` (which users call; it returns a
    :class:`~visviva.simulation.Solution` instead of raising on a numerical failure).

    Args:
        problem: A :class:`~visviva.ode.FirstOrderProblem` or
            :class:`~visviva.ode.SecondOrderProblem`.
        method: Integrator name or instance (see ``vv.integrators.names()``).
        dt: Step [s]; must be positive.
        until: End time [s]; must not be before the problem's ``t0``.
        substeps: Integrator steps per step (each of ``dt/substeps``).
        record_every: Record every k-th step (the initial and the final state always).
        progress: Show a progress bar on long runs (default: only if stderr is a terminal).
        divergence_limit: Largest allowed ``|component|`` before the run counts as diverged
            (default ``1e10 × max(1, max |initial state|)``).
        compiled: ``None`` to run compiled when possible, ``False`` to force the NumPy path,
            ``True`` to require the compiled path.
        on_frame: Called with ``(state, energy)`` as each frame is recorded, for example to
            stream frames to a file while the run goes on.

    Returns:
        The :class:`~visviva.simulation.recording.Recording`, with fields ``y``
        (first-order) or ``q`` and ``v``, plus ``energy`` if the problem defines it; its
        ``attrs`` hold the method, step, work counters and wall time.

    Raises:
        ModelError: For invalid arguments, before any step.
        SimulationDiverged: If the state blows up; ``error.recording`` holds the frames so far.
        NewtonConvergenceError: If an implicit step fails; ``error.recording`` likewise.
        Interrupted: If a stop was requested by a signal (see
            :mod:`~visviva.simulation.interrupt`); ``error.recording`` likewise.
    """
    check_problem(problem)
    integrator = get(method)
    dt = real_number("dt", dt, positive=True, unit=" s")
    until = check_end_time(problem, until)
    span = until - problem.t0
    if dt > span > 0.0:
        raise ModelError(
            f"`dt` ({dt!r} s) is longer than the run (until - t0 = {span!r} s); use dt <= {span!r}"
        )
    substeps = whole_number("substeps", substeps, minimum=1)
    if span / dt * substeps > MAX_STEPS:
        raise ModelError(
            f"`dt` ({dt!r} s) with {substeps} substep(s) would take "
            f"{span / dt * substeps:.3g} integrator steps to reach `until`; the limit is "
            f"{MAX_STEPS:.0e} (use a larger dt or fewer substeps)"
        )
    record_every = whole_number("record_every", record_every, minimum=1)
    if divergence_limit is not None:
        divergence_limit = real_number("divergence_limit", divergence_limit, positive=True)
    system = problem.system()
    integrator.check(system)
    compiled_step = _compiled_step(integrator, problem, compiled)

    schedule = Schedule.build(problem.t0, until, dt, substeps)
    state = problem.initial_state()
    recorder = FrameRecorder(system, state, on_frame=on_frame)
    watch = DivergenceWatch(system, integrator, dt, state, divergence_limit)
    stepper = Stepper(system, integrator, watch)
    attrs: dict[str, Any] = {
        "method": integrator.name,
        "dt": dt,
        "substeps": substeps,
        "record_every": record_every,
        "t0": problem.t0,
        "until": until,
        "problem": problem.name,
        "kind": problem.kind,
        "conservative": problem.conservative,
        "batch_size": problem.batch_size,
        "compiled": compiled_step is not None,
        "visviva_version": __version__,
    }
    started = time.perf_counter()
    error: SimulationError | Interrupted | None = None
    with Progress(schedule.steps, f"{integrator.name}", progress) as bar:
        try:
            if compiled_step is None:
                advance(stepper, state, schedule, record_every, recorder, bar)
            else:
                _run_compiled(
                    compiled_step,
                    problem,
                    system,
                    state,
                    schedule,
                    record_every,
                    recorder,
                    watch,
                    bar,
                )
        except (SimulationError, Interrupted) as failure:
            error = failure
    attrs["wall_time_s"] = time.perf_counter() - started
    attrs["steps"] = system.counters.accepted_steps
    attrs |= system.counters.as_dict()
    attrs["success"] = attrs["complete"] = error is None
    attrs["message"] = "completed" if error is None else str(error)
    if isinstance(error, Interrupted):
        attrs["interrupted"] = error.signal
    recording = recorder.recording(attrs)
    if error is not None:
        error.recording = recording
        raise error
    return recording


def check_problem(problem: Any) -> None:
    """Refuse anything that is not one of the problem kinds."""
    from ..ode.problems import FirstOrderProblem, SecondOrderProblem

    if not isinstance(problem, (FirstOrderProblem, SecondOrderProblem)):
        raise ModelError(
            "`problem` must be a vv.ode.FirstOrderProblem or vv.ode.SecondOrderProblem "
            f"(got {type(problem).__name__})"
        )


def check_end_time(problem: Problem, until: Any) -> float:
    """``until`` as a float, not before the problem's ``t0``."""
    until = real_number("until", until, unit=" s")
    if until < problem.t0:
        raise ModelError(f"`until` ({until!r}) must not be before t0 ({problem.t0!r})")
    return until


def _compiled_step(
    integrator: Integrator, problem: Problem, compiled: bool | None
) -> CompiledStep | None:
    if compiled is False:
        return None
    step = integrator.compiled_step(problem)
    if step is None and compiled:
        raise ModelError(
            f"compiled=True needs Numba functions and a method with a compiled step "
            f"(explicit fixed-step methods); {integrator.name!r} with this problem has none"
        )
    return step


def advance(
    stepper: Stepper,
    state: State,
    schedule: Schedule,
    record_every: int,
    recorder: FrameSink | None,
    bar: Progress,
) -> State:
    """Run ``schedule`` from ``state`` through ``stepper``: the one fixed-step loop.

    A frame is recorded after every ``record_every``-th step counted from the grid's origin,
    after the last step, and when a stop was requested (then :class:`Interrupted` is raised
    with that frame's time). Returns the final state (pass it through
    :meth:`Stepper.settled` before reading its arrays).
    """
    substeps = schedule.substeps
    done = state
    for step in range(schedule.steps):
        current = done
        sub = 0
        try:
            for sub in range(substeps):
                h, t_after = schedule.substep(step, sub)
                index = (schedule.first + step) * substeps + sub
                current = stepper.step(current, h, t_after, index, boundary=sub == 0)
        except SimulationError as failure:
            failure.state, failure.steps_done = stepper.earlier(done, sub + 1), step
            raise
        except Interrupted as asked:  # by a solve between its iterations: drop the half step
            settled = stepper.settled(done)
            if recorder is not None and recorder.last().t != settled.t:
                recorder.append(settled)  # the last whole step is the last frame
            cut = Interrupted(asked.signal, settled.t)
            cut.state, cut.steps_done = settled, step
            raise cut from None
        done = current
        last = step + 1 == schedule.steps
        stop = stop_requested()
        if recorder is not None and (
            (schedule.first + step + 1) % record_every == 0 or last or stop
        ):
            recorder.append(stepper.settled(done))
        bar.advance(1)
        if stop is not None and not last:
            interrupted = Interrupted(stop, done.t)
            interrupted.state, interrupted.steps_done = stepper.settled(done), step + 1
            raise interrupted
    return done


def _stack(state: State) -> np.ndarray:
    """The state as ``(batch, m)`` rows: ``y``, or ``[q, v]`` side by side."""
    parts = [p if p.ndim == 2 else p[None, :] for p in state.parts]
    return np.ascontiguousarray(np.concatenate(parts, axis=1))


def _run_compiled(
    step: CompiledStep,
    problem: Problem,
    system: System,
    state: State,
    schedule: Schedule,
    record_every: int,
    recorder: FrameRecorder,
    watch: DivergenceWatch,
    bar: Progress,
) -> None:
    """The same schedule, frames and watch as :func:`advance`, in compiled chunks."""
    from ..integrators.compiled import make_runner

    batch = state.parts[0].ndim == 2
    y = _stack(state)
    systems, m = y.shape
    run = make_runner(step, systems)
    work = np.zeros((systems, step.rows, m), dtype=y.dtype)
    status = np.full(systems, -1, dtype=np.int64)
    evaluations = np.zeros(systems, dtype=np.int64)
    substeps = schedule.substeps

    def advance(
        origin: float,
        h: float,
        first: int,
        count: int,
        every: int,
        frames: int,
        offset: int,
        fresh: bool,
    ) -> None:
        """Run substeps ``first … first + count − 1`` of size ``h`` timed from ``origin``.

        A frame is recorded after every ``every``-th substep; ``offset`` is the index of the
        first substep in the whole run (for messages).
        """
        buffer = np.empty((frames, systems, m), dtype=y.dtype)
        run(
            y, work, fresh, origin, h, first, count, every, buffer, watch.limit, status, evaluations
        )
        system.counters.f_evaluations = int(evaluations.max())
        failed = status >= 0
        done = count if not failed.any() else int(status[failed].min()) - first
        system.counters.accepted_steps += done
        valid = min(frames, done // every)
        times = origin + (first + every * np.arange(1, valid + 1)) * h
        if valid and offset + valid * every == schedule.steps * substeps:
            times[-1] = schedule.until
        recorder.extend(times, buffer[:valid], batch)
        if done < count:
            bad = state.from_parts(origin + (first + done + 1) * h, _unstack(y, state))
            raise watch.diverged(bad, offset + done, recorder.last())

    h = schedule.h
    per_frame = record_every * substeps
    chunk_frames = max(1, CHUNK_SYSTEM_STEPS // (systems * per_frame))
    done = 0  # full steps done
    while done < schedule.full_steps:
        remaining = schedule.full_steps - done
        if remaining >= record_every:
            frames = min(chunk_frames, remaining // record_every)
            steps, every = frames * record_every, per_frame
        else:
            # The tail after the last multiple of record_every: a frame only if the run ends.
            steps = remaining
            frames = 1 if schedule.last_dt == 0.0 else 0
            every = steps * substeps if frames else steps * substeps + 1
        first = done * substeps
        advance(schedule.t0, h, first, steps * substeps, every, frames, first, done == 0)
        done += steps
        bar.advance(steps)
        if done < schedule.full_steps or schedule.last_dt > 0.0:
            name = stop_requested()
            if name is not None:
                raise Interrupted(name, recorder.last().t)
    if schedule.last_dt > 0.0:
        start = schedule.t0 + schedule.full_steps * substeps * h
        advance(
            start,
            schedule.last_dt / substeps,
            0,
            substeps,
            substeps,
            1,
            schedule.full_steps * substeps,
            schedule.full_steps == 0,
        )
        bar.advance(1)


def _unstack(y: np.ndarray, template: State) -> tuple[np.ndarray, ...]:
    """The integrated arrays of ``template``'s shapes from the stacked rows ``y``."""
    rows = y if template.parts[0].ndim == 2 else y[0]
    sizes = np.cumsum([part.shape[-1] for part in template.parts])[:-1]
    return tuple(piece.copy() for piece in np.split(rows, sizes, axis=-1))
