"""Keeping the frames of a run in memory: :class:`FrameRecorder`.

Frames are the named parts of the recorded states (``y``; ``q`` and ``v``; a scene's
``particle_position`` ...) and the system's energy at each of them, evaluated as the frame is
recorded. Runs that stream their frames to a file instead pass ``on_frame`` and keep nothing
(:mod:`visviva.simulation.simulation`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from .recording import Recording

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.system import System

__all__ = ["FrameCallback", "FrameRecorder", "FrameSink"]

#: ``on_frame(state, energy)``: a recorded state and its energy (``None`` if the system has
#: none). The state's arrays belong to the run: copy what you keep.
FrameCallback = Callable[["State", "np.ndarray | None"], None]


class FrameSink(Protocol):
    """What the loop records frames into (a :class:`FrameRecorder`, or an ensemble's)."""

    def append(self, state: State) -> None:
        """Record ``state`` as the next frame."""


class FrameRecorder:
    """Collects the frames of a run.

    Args:
        system: The system being run (for the energy of each frame).
        template: A state of the run (its layout and shapes); recorded as the first frame
            unless ``include`` is false.
        include: Record ``template`` as the first frame.
        on_frame: Called with every frame as it is recorded (streaming writers).
        keep: Keep the frames in memory (``False`` when ``on_frame`` streams them elsewhere;
            :meth:`recording` then holds only the last frame).
    """

    def __init__(
        self,
        system: System,
        template: State,
        include: bool = True,
        on_frame: FrameCallback | None = None,
        keep: bool = True,
    ) -> None:
        self.system = system
        self.template = template
        self.on_frame = on_frame
        self.keep = keep
        self.times: list[float] = []
        self.fields: dict[str, list[np.ndarray]] = {name: [] for name, _ in template.named()}
        self.energy: list[np.ndarray] = []
        self._last = template
        if include:
            self.append(template)

    def append(self, state: State) -> None:
        """Record ``state`` as the next frame (copied)."""
        energy = self.system.energy(state)
        self._last = state
        if self.keep:
            self.times.append(state.t)
            for name, part in state.named():
                self.fields[name].append(np.array(part))
            if energy is not None:
                self.energy.append(energy)
        if self.on_frame is not None:
            self.on_frame(state, energy)

    def extend(self, times: np.ndarray, stacked: np.ndarray, batch: bool) -> None:
        """Append frames from the compiled path: ``stacked`` is ``(frames, batch, m)``, each
        row the integrated arrays side by side."""
        sizes = np.cumsum([part.shape[-1] for part in self.template.parts])[:-1]
        for t, frame in zip(times, stacked, strict=True):
            pieces = np.split(frame if batch else frame[0], sizes, axis=-1)
            self.append(self.template.from_parts(float(t), tuple(np.array(p) for p in pieces)))

    def last(self) -> State:
        """The most recent frame's state."""
        return self._last

    def recording(self, attrs: dict[str, Any]) -> Recording:
        """The frames so far as a :class:`Recording` with ``attrs`` (fields: the named parts
        and, if the system defines it, ``energy``)."""
        fields = {
            name: np.stack(store) if store else np.empty((0, *part.shape), part.dtype)
            for (name, part), store in zip(self.template.named(), self.fields.values(), strict=True)
        }
        if self.energy:
            fields["energy"] = np.array(self.energy, dtype=np.float64)
        return Recording(np.array(self.times, dtype=np.float64), fields, attrs=attrs)
