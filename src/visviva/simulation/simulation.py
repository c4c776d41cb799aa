"""Driving a scene from Python: ``vv.Simulation(model)``, step by step.

For people who write their own loop around a simulation (as with MuJoCo's ``mj_step`` or
pymunk's ``space.step``)::

    sim = vv.Simulation(model)
    sim.step()                          # one step of dt
    sim.run(until=2.0)                  # lands exactly on t = 2 s
    recording = sim.record(until=3.0)   # the same, keeping the frames in memory
    sim.time, sim.energy()
    sim.state["particle_position"]      # the live particles, (n, 3), in slot order
    blob = sim.checkpoint()             # bytes
    again = vv.Simulation.restore(model, blob)   # continues bit for bit

Each step is the pipeline's (:class:`~visviva.simulation.stepper.Stepper`): the integrator,
then the model's stages (collisions, births and deaths), then the divergence watch; the runs of
``visviva run`` go through :meth:`Simulation.run` too. Time is counted on the grid
``origin + k·dt/substeps`` from integer counters, so a run split into pieces — or checkpointed,
restored and continued — takes exactly the steps of one long run.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import weakref
from collections.abc import Iterator, Mapping
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np

from .._compiling import watch_compiles
from .._validation import real_number, whole_number
from ..collision.body_contacts import BodyContactSet
from ..collision.contact_classes import DEFAULT_GAP, Contacts
from ..collision.particle_contacts import PairContacts
from ..errors import ModelError, SimulationError
from ..integrators import Integrator, get
from ..model.model import MAX_STEPS
from ..ode.state import State
from .frames import UNITS, frame_fields, recording_attrs, static_fields
from .interrupt import Interrupted
from .loop import Schedule, advance
from .progress import Progress
from .recorder import FrameCallback, FrameRecorder
from .recording import Recording
from .stepper import Stepper
from .watch import DivergenceWatch

if TYPE_CHECKING:
    from ..model import Model
    from ..rigid.bodies import BodyViews

__all__ = ["CHECKPOINT_FORMAT", "Simulation", "SimulationState"]

#: Format tag and version of checkpoints (:meth:`Simulation.checkpoint`).
CHECKPOINT_FORMAT = "visviva.checkpoint"
CHECKPOINT_VERSION = 1
#: Parts that describe particles one per slot: :class:`SimulationState` shows the live ones.
_PER_PARTICLE = ("particle_",)


class SimulationState(Mapping[str, np.ndarray]):
    """A read-only view of a simulation's state by part name.

    Particle parts (``particle_position``, ``particle_velocity``, ``particle_radius``, ...)
    hold the live particles only, in slot order: ``(n, 3)`` or ``(n,)``. Other parts
    (``generalized_position``, ...) are whole. Values are copies, safe to keep, and so is the
    view: it reads the state of its time ``t`` even after the simulation has gone on (a view
    kept across a step copies its state before the step).

    Attributes:
        t: Time [s].
    """

    def __init__(self, state: State) -> None:
        self._state = state
        self.t = state.t
        alive = state.carried.get("particle_alive")
        self._alive = None if alive is None or alive.all() else alive

    def __getitem__(self, name: str) -> np.ndarray:
        values = np.array(self._state[name])
        if self._alive is not None and name.startswith(_PER_PARTICLE):
            values = values[self._alive]
        values.flags.writeable = False
        return values

    def __iter__(self) -> Iterator[str]:
        return iter(self._state.names())

    def __len__(self) -> int:
        return len(self._state.names())

    def __repr__(self) -> str:
        return f"SimulationState(t={self.t!r}, parts: {', '.join(self)})"

    def _keep(self) -> None:
        """Hold copies of the state's arrays: the simulation is about to change them."""
        state = self._state
        self._state = State(
            state.t,
            tuple(np.array(part) for part in state.parts),
            state.layout,
            {name: np.array(value) for name, value in state.carried.items()},
        )
        if self._alive is not None:
            self._alive = self._state.carried["particle_alive"]


class Simulation:
    """A scene in motion (see the module docstring).

    Args:
        model: The built scene (``vv.load_model(path)`` or ``vv.SceneBuilder(...).build()``).
        method: Integrator name or instance (default: the scene's).
        dt: Step [s] (default: the scene's); each step is the scene's ``substeps``
            integrator steps.
        divergence_limit: Largest allowed ``|component|`` before the run counts as diverged
            (default ``1e10 × max(1, max |initial state|)``).
        compiled: ``None`` to take the fused step when the scene has one (one parallel pass
            per step: :mod:`visviva.particles.fused` for particles,
            :mod:`visviva.rigid.fused` for rigid bodies), ``False`` for the generic pipeline,
            ``True`` to require the fused step.

    Raises:
        ModelError: If the method cannot integrate the scene or an argument is invalid.
    """

    def __init__(
        self,
        model: Model,
        *,
        method: str | Integrator | None = None,
        dt: float | None = None,
        divergence_limit: float | None = None,
        compiled: bool | None = None,
    ) -> None:
        from ..particles.fused import FusedParticles
        from ..rigid.fused import FusedBodies

        watch_compiles()
        settings = model.integration
        self.model = model
        self.integrator = get(settings.method if method is None else method)
        self.dt = settings.dt if dt is None else real_number("dt", dt, positive=True, unit=" s")
        self.substeps = settings.substeps
        self.system = model.system()
        self.integrator.check(self.system)
        state = model.initial_state()
        if divergence_limit is not None:
            divergence_limit = real_number("divergence_limit", divergence_limit, positive=True)
        watch = DivergenceWatch(self.system, self.integrator, self.dt, state, divergence_limit)
        fused = None
        if compiled is not False:
            method = self.integrator.name
            fused = FusedParticles.of(model, method) or FusedBodies.of(model, method)
        if compiled and fused is None:
            raise ModelError(
                "compiled=True needs a scene made only of particles under field forces, with "
                "colliders and emitters, or only of rigid bodies under gravity and damping, "
                "stepped by 'symplectic_euler'; this one has no fused step"
            )
        self._stepper = Stepper(self.system, self.integrator, watch, model.stages, fused)
        self._state = state
        self._views: list[weakref.ref[SimulationState]] = []  # handed out since the last step
        self._origin = state.t
        self._steps = 0  # steps of dt since the origin

    @property
    def time(self) -> float:
        """The simulated time [s]."""
        return self._state.t

    @property
    def state(self) -> SimulationState:
        """The current state by part name (live particles only; see :class:`SimulationState`)."""
        view = SimulationState(self._current())
        self._views = [ref for ref in self._views if ref() is not None]
        self._views.append(weakref.ref(view))
        return view

    @property
    def compiled(self) -> bool:
        """True if the steps are fused into one compiled pass (see ``compiled`` above)."""
        return self._stepper.fused is not None

    @property
    def raw_state(self) -> State:
        """The whole state: every particle slot, dead ones included, and the carried parts.

        The next step changes its arrays in place: copy what you keep."""
        return self._current()

    def contacts(self, gap: float = DEFAULT_GAP) -> Contacts:
        """The particles' contacts with the colliders now: which particle touches which
        collider (within its radius plus ``gap`` [m]), where, how deep, and whether it is
        colliding, resting or separating (see :mod:`visviva.collision.contact_classes`)."""
        gap = real_number("gap", gap, unit=" m")
        if gap < 0.0:
            raise ModelError(f"`gap` must be >= 0 (got {gap!r} m)")
        return self.model.contacts(self._current(), gap)

    def pair_contacts(self, gap: float = DEFAULT_GAP) -> PairContacts:
        """The sphere–sphere contacts now among the particles that collide with each other
        (a scene's ``particle_collisions``): which pairs touch (surfaces within ``gap`` [m]),
        where, how deep, and whether colliding, resting or separating
        (:class:`~visviva.collision.particle_contacts.PairContacts`).

        Raises:
            ModelError: If the scene's particles do not collide with each other.
        """
        gap = real_number("gap", gap, nonnegative=True, unit=" m")
        return self.model.pair_contacts(self._current(), gap)

    def body_contacts(self, gap: float = DEFAULT_GAP) -> BodyContactSet:
        """The rigid bodies' contacts now, with each other and with the colliders (a scene's
        ``body_contacts``): which pieces touch (within ``gap`` [m]), where, along which
        normal, how deep, and whether colliding, resting or separating
        (:class:`~visviva.collision.body_contacts.BodyContactSet`).

        Raises:
            ModelError: If the scene's bodies do not collide.
        """
        gap = real_number("gap", gap, nonnegative=True, unit=" m")
        return self.model.body_contacts(self._current(), gap)

    def bodies(self) -> BodyViews:
        """What the rigid bodies' state implies now: ``v``, ``R``, the world inverse inertia
        and ``ω`` of each body (:class:`~visviva.rigid.bodies.BodyViews`).

        Raises:
            ModelError: If the scene has no rigid bodies.
        """
        if self.model.bodies is None:
            raise ModelError("this scene has no rigid bodies (add one with add_body)")
        state = self._current()
        return self.model.bodies.views(
            state["body_orientation"], state["body_momentum"], state["body_angular_momentum"]
        )

    def energy(self) -> float:
        """Kinetic plus potential energy [J] of the live particles and the systems."""
        state = self._current()
        energy = self.system.energy(state)
        return math.nan if energy is None else float(energy)

    def step(self, count: int = 1) -> None:
        """Advance ``count`` steps of ``dt``.

        Raises:
            SimulationDiverged: If the state blows up (the simulation keeps the state at the
                end of the last whole step that was good).
            NewtonConvergenceError: If an implicit step fails (likewise).
        """
        count = whole_number("count", count, minimum=1)
        self._check_budget(count)
        schedule = Schedule(
            self._origin,
            self._origin + (self._steps + count) * self.dt,
            self.dt,
            self.substeps,
            count,
            0.0,
            self._steps,
        )
        self._advance(schedule, None, 1, False)

    def run(
        self,
        until: float,
        *,
        record_every: int = 1,
        on_frame: FrameCallback | None = None,
        progress: bool | None = False,
    ) -> None:
        """Advance to time ``until`` [s] exactly (the last step shortened if it must be).

        Args:
            until: The time to reach [s], not before :attr:`time`.
            record_every: Call ``on_frame`` after every k-th step counted from the start, and
                after the last step.
            on_frame: Called with ``(state, energy)`` for each recorded step.
            progress: Show a progress bar (``None``: if stderr is a terminal).
        """
        until = real_number("until", until, unit=" s")
        if until < self.time:
            raise ModelError(f"`until` ({until!r} s) is before the current time {self.time!r} s")
        if until == self.time:
            return
        record_every = whole_number("record_every", record_every, minimum=1)
        schedule = Schedule.build(self._origin, until, self.dt, self.substeps, self._steps)
        self._check_budget(schedule.steps)
        self._advance(schedule, on_frame, record_every, progress)

    def record(
        self,
        until: float,
        *,
        record_every: int | None = None,
        progress: bool | None = False,
        contacts: bool = False,
    ) -> Recording:
        """Run to ``until`` [s] like :meth:`run`, keeping the frames in memory.

        Each frame is what a recording file keeps of the state (``points``, ``alive``, ...:
        :meth:`Model.frame <visviva.model.Model.frame>`) plus ``energy``; the current state is
        the first frame. For notebooks, demos and small scenes: a long run of many particles
        streams its frames to a file instead (``vv.run_scene``).

        Args:
            until: The time to reach [s].
            record_every: Keep every k-th step (default: the scene's ``record_every``).
            progress: Show a progress bar (``None``: if stderr is a terminal).
            contacts: Also keep the rigid bodies' contacts of each frame (a scene with
                ``body_contacts``): ``body_contact_point`` and ``body_contact_normal``
                ``(frames, K, 3)`` and ``body_contact_class`` ``(frames, K)`` (0 colliding,
                1 resting, 2 separating, -1 an empty slot: frames have up to ``K``), which
                the web viewer draws on demand.

        Raises:
            SimulationDiverged, NewtonConvergenceError, Interrupted: As :meth:`run`; the error's
                ``recording`` holds the frames kept so far.
        """
        if contacts:
            self.model.body_contacts(self._current())  # refused here if there are none
        every = self.model.integration.record_every if record_every is None else record_every
        times: list[float] = []
        frames: list[dict[str, np.ndarray]] = []

        def keep(state: State, energy: np.ndarray | None) -> None:
            fields = {
                name: np.array(value) for name, value in frame_fields(self.model, state).items()
            }
            if energy is not None:
                fields["energy"] = np.asarray(energy, dtype=np.float64)
            if contacts:
                found = self.model.body_contacts(state)
                fields["body_contact_point"] = found.point
                fields["body_contact_normal"] = found.normal
                fields["body_contact_class"] = found.kind
            times.append(state.t)
            frames.append(fields)

        def recording() -> Recording:
            fields = {name: _stacked([f[name] for f in frames]) for name in frames[0]}
            attrs = {
                "method": self.integrator.name,
                "dt": self.dt,
                "substeps": self.substeps,
                "scene_name": self.model.name,
                "steps": self.system.counters.accepted_steps,
            }
            attrs |= self.system.counters.as_dict() | recording_attrs(self.model)
            return Recording(
                np.array(times),
                fields,
                units=UNITS,
                attrs=attrs,
                static=static_fields(self.model),
            )

        state = self._current()
        keep(state, self.system.energy(state))
        try:
            self.run(until, record_every=every, on_frame=keep, progress=progress)
        except (SimulationError, Interrupted) as stopped:
            cut = recording()
            # As solve() marks a run that stopped early: complete, success, why.
            cut.attrs |= {"complete": False, "success": False, "message": str(stopped)}
            if isinstance(stopped, Interrupted):
                cut.attrs["interrupted"] = stopped.signal
            stopped.recording = cut
            raise
        return recording()

    def _current(self) -> State:
        """The current state, its arrays up to date (the fused step works on a copy)."""
        return self._stepper.settled(self._state)

    def _check_budget(self, steps: int) -> None:
        if steps * self.substeps > MAX_STEPS:
            raise ModelError(
                f"{steps * self.substeps:.3g} integrator steps in one call; the limit is "
                f"{MAX_STEPS:.0e} (use a larger dt, or run in pieces)"
            )

    def _advance(
        self,
        schedule: Schedule,
        on_frame: FrameCallback | None,
        record_every: int,
        progress: bool | None,
    ) -> None:
        for ref in self._views:  # the steps change the arrays the views read
            view = ref()
            if view is not None:
                view._keep()
        self._views = []
        recorder = None
        if on_frame is not None:
            recorder = FrameRecorder(self.system, self._current(), False, on_frame, keep=False)
        with Progress(schedule.steps, self.integrator.name, progress) as bar:
            try:
                self._state = advance(
                    self._stepper, self._state, schedule, record_every, recorder, bar
                )
            except (SimulationError, Interrupted) as stopped:
                # Keep the last good state, on the grid: the next step continues from it.
                self._state = stopped.state
                self._steps = schedule.first + stopped.steps_done
                raise
        if schedule.last_dt > 0.0:
            self._origin, self._steps = schedule.until, 0
        else:
            self._steps = schedule.first + schedule.full_steps

    def checkpoint(self) -> bytes:
        """Everything needed to continue this simulation bit for bit, as bytes.

        Restore with :meth:`Simulation.restore` on the same model (checked by a fingerprint of
        the scene).
        """
        state = self._current()
        header = {
            "format": CHECKPOINT_FORMAT,
            "version": CHECKPOINT_VERSION,
            "model": fingerprint(self.model),
            "method": self.integrator.name,
            "dt": self.dt,
            "origin": self._origin,
            "steps": self._steps,
            "t": state.t,
            "derivative": state.derivative is not None,
            "carried": list(state.carried),
        }
        arrays = {f"part{i}": part for i, part in enumerate(state.parts)}
        arrays |= {f"carried_{name}": value for name, value in state.carried.items()}
        if state.derivative is not None:
            arrays |= {f"derivative{i}": d for i, d in enumerate(state.derivative)}
        buffer = io.BytesIO()
        np.savez(buffer, header=np.frombuffer(json.dumps(header).encode(), np.uint8), **arrays)
        return buffer.getvalue()

    @classmethod
    def restore(
        cls, model: Model, blob: bytes, *, method: str | Integrator | None = None
    ) -> Simulation:
        """The simulation a :meth:`checkpoint` of ``model`` saved, ready to continue.

        Raises:
            ModelError: If ``blob`` is not a checkpoint, or one of another scene.
        """
        try:
            with np.load(io.BytesIO(blob), allow_pickle=False) as saved:
                header = json.loads(bytes(saved["header"]).decode())
                arrays = {name: np.array(saved[name]) for name in saved.files}
        except (OSError, ValueError, KeyError, TypeError, UnicodeDecodeError) as error:
            raise ModelError(f"this is not a visviva checkpoint ({type(error).__name__})") from None
        if header.get("format") != CHECKPOINT_FORMAT or header.get("version") != CHECKPOINT_VERSION:
            raise ModelError("this is not a visviva checkpoint of a version this visviva reads")
        if header["model"] != fingerprint(model):
            raise ModelError(
                "this checkpoint was made with another scene: restore it with the model it was "
                "saved from"
            )
        simulation = cls(model, method=method or header["method"], dt=header["dt"])
        template = simulation._state
        parts = tuple(arrays[f"part{i}"] for i in range(len(template.parts)))
        carried = MappingProxyType({name: arrays[f"carried_{name}"] for name in header["carried"]})
        derivative = None
        if header["derivative"]:
            derivative = tuple(arrays[f"derivative{i}"] for i in range(len(template.parts)))
        simulation._state = State(header["t"], parts, template.layout, carried, derivative)
        simulation._origin, simulation._steps = header["origin"], header["steps"]
        return simulation


def fingerprint(model: Model) -> str:
    """A digest of the scene description a model was built from."""
    text = model.scene.model_dump_json()
    return hashlib.sha256(text.encode()).hexdigest()


def _stacked(values: list[np.ndarray]) -> np.ndarray:
    """Frames of one field stacked; frames of different lengths (a field of contacts) padded
    to the longest, with -1 for whole numbers and NaN for real ones."""
    longest = max(v.shape[0] if v.ndim else 0 for v in values)
    if all(v.shape == values[0].shape for v in values):
        return np.stack(values)
    padded = []
    for v in values:
        fill = -1 if np.issubdtype(v.dtype, np.integer) else np.nan
        extra = np.full((longest - v.shape[0], *v.shape[1:]), fill, dtype=v.dtype)
        padded.append(np.concatenate([v, extra]))
    return np.stack(padded)
