"""Ensembles: many runs of one model advancing side by side in one batched state.

A sweep over initial conditions — a thousand double pendulums released from a thousand angles —
runs the same equations a thousand times; a sweep over a ball's restitution runs the same
particle scene with other values. Where the models allow it (:func:`ensemble_key`), the members
advance as one batch through the one loop (:func:`~visviva.simulation.loop.advance`): one
evaluation of the equations, or one pass of each particle kernel, per stage for the whole
batch instead of one per member, and no process per member. Two kinds of models batch:

* **one named system each**, sharing their compiled equations
  (:func:`~visviva.ode.stacking.equations_key`: same parameters, only the start differs): the
  members are the rows of one batched problem (:func:`~visviva.ode.stacking.stack`). Each
  computes exactly what its own run computes, bit for bit: the same explicit or symplectic
  method, step schedule, recorded frames and energy, with the batch's row ``i`` evaluated by
  member ``i``'s function;
* **particle scenes with the same entities** (:func:`~visviva.model.replicas.replica_key`:
  particles and bodies of springs under force fields, with colliders; any values may differ):
  the members are the particle spans of one model (:class:`~visviva.model.replicas.Replicas`),
  each particle under its own member's forces and colliders. Each member's figures are those of
  its own run to round-off (bit for bit where the merged model sums each force by the same
  path; see :mod:`visviva.model.replicas`).

Implicit methods do not batch: their Newton iterations would run until every member converged.
The divergence watch uses the smallest of the members' limits; a member that fails (diverges,
or takes the batch down with a failure that names no member) is taken out of the batch, which
goes on from its last good state without it, and is reported so that the caller runs it alone,
where it fails exactly as it would have (with its own limit and message).
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .._compiling import watch_compiles
from ..errors import ModelError, SimulationDiverged, SimulationError
from ..integrators import Integrator, get
from ..ode.stacking import equations_key, stack
from ..ode.state import State
from .loop import Schedule, advance
from .progress import Progress
from .stepper import Stepper
from .watch import DivergenceWatch

if TYPE_CHECKING:
    from ..model import Model
    from ..ode.stage import Stage
    from ..ode.system import System
    from .stepper import FusedStep

__all__ = [
    "MAX_MEMBER_PARTICLES",
    "EnsembleFrame",
    "EnsembleRun",
    "ensemble_capacity",
    "ensemble_key",
    "run_ensemble",
]

#: Most particles a member of a particle ensemble may hold: beyond, one member's step is
#: long enough that a batch saves little, and each particle's collider copies (one per
#: member, where a collider's values differ) cost more than the batch saves
#: (``benchmarks/bench_particle_sweeps.py``).
MAX_MEMBER_PARTICLES = 1_000


def ensemble_key(model: Model) -> Hashable | None:
    """What models must share to advance in one batch (see the module docstring), or
    ``None`` if ``model`` cannot join one: it is neither one named system nor a particle
    scene of replicas (or has more than :data:`MAX_MEMBER_PARTICLES` particles), its named
    system's problem cannot be stacked, or its method is implicit (Newton's iterations run
    until every member of a batch has converged, so a member would take other iterations
    than alone). The key compares equal only within one process (it may hold functions)."""
    from ..model.replicas import replica_key

    settings = model.integration
    if get(settings.method).implicit:
        return None
    if model.particle_count:
        if model.particle_count > MAX_MEMBER_PARTICLES:
            return None
        replicas = replica_key(model.scene)
        return None if replicas is None else ("particles", replicas)
    if model.body_count or model.stages or len(model.systems) != 1:
        return None
    equations = equations_key(model.systems[0].problem)
    if equations is None:
        return None
    timing = (settings.method, settings.dt, settings.duration, settings.substeps)
    return ("system", equations, *timing, settings.record_every)


def ensemble_capacity(models: Sequence[Model]) -> int:
    """How many of ``models`` (one :func:`ensemble_key`) one batch may hold: all of them for
    named systems; for particle scenes, as many as one merged model has room for
    (:func:`~visviva.model.replicas.replica_capacity`)."""
    from ..model.replicas import replica_capacity

    if not models or not models[0].particle_count:
        return len(models)
    return replica_capacity([m.scene for m in models])


class EnsembleFrame:
    """A recorded frame of an ensemble's batch.

    Attributes:
        t: Its time [s].
        members: The members in the batch, as indices into the models given.
        energy: Each one's energy [J], ``(len(members),)``, or ``None``.
    """

    def __init__(
        self,
        batch: _Batch,
        state: State,
        members: Sequence[int],
        energy: np.ndarray | None,
    ) -> None:
        self.t = state.t
        self.members = tuple(members)
        self.energy = energy
        self._batch = batch
        self._state = state

    def state(self, k: int) -> State:
        """Member ``members[k]``'s own state, as its own run holds it (arrays copied)."""
        return self._batch.member_state(self._state, k)

    def kept(self) -> EnsembleFrame:
        """This frame with copies of the batch's arrays (later steps change them in place)."""
        state = self._state
        copy = State(
            state.t,
            tuple(np.array(p) for p in state.parts),
            state.layout,
            {name: np.array(value) for name, value in state.carried.items()},
        )
        return EnsembleFrame(self._batch, copy, self.members, self.energy)


#: ``on_frame(frame)``: a recorded frame of the batch, at the times each member's own run
#: records (see :class:`EnsembleFrame`); its arrays belong to the run.
EnsembleFrameCallback = Callable[[EnsembleFrame], None]


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
    on_frame: EnsembleFrameCallback | None = None,
    progress: bool | None = False,
) -> EnsembleRun:
    """Run every model of an ensemble from its start to ``until`` [s] in one batch.

    Args:
        models: Models with one :func:`ensemble_key`, at most :func:`ensemble_capacity`
            (checked).
        until: End time [s], as for :meth:`Simulation.run <visviva.simulation.Simulation.run>`.
        on_frame: Called with each recorded frame of the batch (the start, every
            ``record_every``-th step and the last). A member that fails has had its frames
            up to the failure passed: discard them.
        progress: Show a progress bar over the batch's steps.

    Returns:
        The shared work counters and the members that failed (see the module docstring).

    Raises:
        ModelError: Models that do not share one key or are too many for one batch, or an
            end before their start.
        Interrupted: On SIGINT/SIGTERM (inside
            :class:`~visviva.simulation.interrupt.StopOnSignal`), after the current step; the
            frames up to it were passed to ``on_frame``.
    """
    watch_compiles()
    if not models:
        raise ModelError("`models` is empty: an ensemble needs at least one model")
    key = ensemble_key(models[0])
    if key is None or any(ensemble_key(m) != key for m in models[1:]):
        raise ModelError(
            "these models cannot advance in one batch: each must be one named system, all "
            "with the same equations (only initial conditions may differ), or a particle "
            "scene with the same entities; all with the same integration settings"
        )
    if len(models) > ensemble_capacity(models):
        raise ModelError(
            f"{len(models)} models exceed the {ensemble_capacity(models)} one batch can hold "
            "(split them with ensemble_capacity)"
        )
    settings = models[0].integration
    integrator = get(settings.method)
    starts = [m.initial_state() for m in models]
    origin = starts[0].t
    if until < origin:
        raise ModelError(f"`until` ({until!r} s) is before the start {origin!r} s")
    make: Callable[[Sequence[Model], Integrator], _Batch]
    make = _Replicated if models[0].particle_count else _Stacked
    states = dict(enumerate(starts))  # each member's state where the batch got to
    members = list(range(len(models)))
    result = EnsembleRun()
    totals: dict[str, int] = {}
    started = time.perf_counter()
    schedule = Schedule.build(origin, until, settings.dt, settings.substeps)
    with Progress(schedule.steps, f"{integrator.name} x{len(models)}", progress) as bar:
        done = 0  # steps of dt taken from the origin
        while members and done < schedule.steps:
            batch = make([models[m] for m in members], integrator)
            state = batch.join([states[m] for m in members])
            # The smallest limit of the members still in: a member stopped by it that its own
            # limit would have let through runs alone, where its own limit applies.
            limit = min(DivergenceWatch.default_limit(starts[m]) for m in members)
            watch = DivergenceWatch(batch.system, integrator, settings.dt, state, limit)
            stepper = _Rewinding(batch.system, integrator, watch, batch.stages, batch.fused)
            piece = Schedule.build(origin, until, settings.dt, settings.substeps, done)
            recorder = _Frames(batch, members, on_frame)
            if done == 0:
                recorder.append(state)
            try:
                advance(stepper, state, piece, settings.record_every, recorder, bar)
                done = schedule.steps
            except SimulationError as failure:
                rows = batch.failed_rows(failure)
                for row in rows:
                    result.failed[members[row]] = str(failure)
                kept = [k for k in range(len(members)) if k not in rows]
                states = {members[k]: batch.member_state(failure.state, k) for k in kept}
                members = [members[k] for k in kept]
                done += failure.steps_done
            finally:
                for name, value in batch.system.counters.as_dict().items():
                    totals[name] = totals.get(name, 0) + value
    result.counters = totals
    result.wall_time_s = time.perf_counter() - started
    return result


class _Batch(ABC):
    """Members advancing as one: the system the integrator steps, its stages and fused step,
    and the passage between the batch's state and each member's."""

    system: System
    stages: tuple[Stage, ...] = ()
    fused: FusedStep | None = None

    @abstractmethod
    def join(self, states: Sequence[State]) -> State:
        """The batch's state whose members are ``states`` (one per member, at one time)."""

    @abstractmethod
    def member_state(self, state: State, k: int) -> State:
        """Member ``k``'s own state (its own layout, arrays copied) from the batch's."""

    @abstractmethod
    def energies(self, state: State) -> np.ndarray | None:
        """Each member's energy [J] in ``state``, ``(members,)``, or ``None``."""

    @abstractmethod
    def failed_rows(self, failure: SimulationError) -> list[int]:
        """The members a failure is about: the one it names, or all if it names none."""


class _Stacked(_Batch):
    """Members that are one named system each, as the rows of one batched problem."""

    def __init__(self, models: Sequence[Model], integrator: Integrator) -> None:
        self.templates = [m.initial_state() for m in models]
        problem = stack([m.systems[0].problem for m in models], name=models[0].name)
        self.system = problem.system()
        self.layout = problem.initial_state().layout
        integrator.check(self.system)

    def join(self, states: Sequence[State]) -> State:
        def rows(arrays: Sequence[tuple[np.ndarray, ...]]) -> tuple[np.ndarray, ...]:
            return tuple(np.stack(parts) for parts in zip(*arrays, strict=True))

        derivatives = [s.derivative for s in states]
        derivative = None
        if all(d is not None for d in derivatives):
            derivative = rows(derivatives)  # type: ignore[arg-type]
        return State(states[0].t, rows([s.parts for s in states]), self.layout, {}, derivative)

    def member_state(self, state: State, k: int) -> State:
        template = self.templates[k]
        derivative = None
        if state.derivative is not None:
            derivative = tuple(np.array(d[k]) for d in state.derivative)
        parts = tuple(np.array(p[k]) for p in state.parts)
        return State(state.t, parts, template.layout, template.carried, derivative)

    def energies(self, state: State) -> np.ndarray | None:
        return self.system.energy(state)

    def failed_rows(self, failure: SimulationError) -> list[int]:
        row = failure.system if isinstance(failure, SimulationDiverged) else None
        return list(range(len(self.templates))) if row is None else [row]


class _Replicated(_Batch):
    """Particle scenes, as the particle spans of one merged model
    (:class:`~visviva.model.replicas.Replicas`)."""

    def __init__(self, models: Sequence[Model], integrator: Integrator) -> None:
        from ..model.replicas import Replicas
        from ..particles.fused import FusedParticles

        self.replicas = Replicas.of(models)
        model = self.replicas.model
        self.system = model.system()
        integrator.check(self.system)
        self.stages = model.stages
        self.fused = FusedParticles.of(model, integrator.name)
        self.own = [m.system() for m in models]  # each member's energy, as its run has it

    def join(self, states: Sequence[State]) -> State:
        return self.replicas.join(states)

    def member_state(self, state: State, k: int) -> State:
        return self.replicas.member_state(state, k)

    def energies(self, state: State) -> np.ndarray | None:
        values = [system.energy(self.member_state(state, k)) for k, system in enumerate(self.own)]
        return None if any(v is None for v in values) else np.array(values, dtype=np.float64)

    def failed_rows(self, failure: SimulationError) -> list[int]:
        entry = failure.entry if isinstance(failure, SimulationDiverged) else None
        if entry is None or entry[1] >= 3 * self.replicas.model.particle_count:
            return list(range(len(self.own)))
        return [self.replicas.member_of(entry[1] // 3)]


class _Frames:
    """Hands each recorded state of a batch to ``on_frame`` as an :class:`EnsembleFrame`
    (what :func:`~visviva.simulation.loop.advance` calls a recorder)."""

    def __init__(
        self, batch: _Batch, members: Sequence[int], on_frame: EnsembleFrameCallback | None
    ) -> None:
        self.batch = batch
        self.members = list(members)
        self.on_frame = on_frame

    def append(self, state: State) -> None:
        if self.on_frame is not None:
            energy = self.batch.energies(state)
            self.on_frame(EnsembleFrame(self.batch, state, self.members, energy))


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
