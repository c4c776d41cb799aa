"""The exceptions visviva raises.

Two families, following the rule "bad input is refused before anything runs; a run that fails
says when, where and what to do":

* :class:`ModelError` (a ``ValueError``) for invalid input: a problem, argument or scene that
  cannot be simulated as given. Raised before the first step.
* :class:`SimulationError` (a ``RuntimeError``) for a numerical failure during a run: the state
  blew up (:class:`SimulationDiverged`) or an implicit solve did not converge
  (:class:`NewtonConvergenceError`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = [
    "Interrupted",
    "ModelError",
    "NewtonConvergenceError",
    "SceneError",
    "SceneProblem",
    "SimulationDiverged",
    "SimulationError",
    "SweepError",
    "VisvivaError",
]


class VisvivaError(Exception):
    """Base class of every exception raised by visviva.

    Attributes:
        recording: The frames recorded before a run stopped (set by the simulation loop).
        report: What a job (``run_scene``, ``run_demo``) wrote before raising, if anything.
        state: The last good state of a run that stopped (set by the simulation loop).
        steps_done: Whole steps of that run before it stopped.
    """

    recording: Any = None
    report: Any = None
    state: Any = None
    steps_done: int = 0


class ModelError(VisvivaError, ValueError):
    """Invalid input: the message names the field, the value received and the fix."""


@dataclass(frozen=True)
class SceneProblem:
    """One thing wrong with a scene.

    Attributes:
        path: Where, as in the file: ``entities[2].mass`` (empty for the whole scene).
        message: What is wrong and how to fix it.
        got: The offending value as written in the message, or ``None``.
        line: Line of the scene file where it can be found (1-based), when known.
    """

    path: str
    message: str
    got: str | None = None
    line: int | None = None

    def describe(self, source: str | None = None) -> str:
        """``file:line: path: message (got X)``."""
        where = ":".join(str(x) for x in (source, self.line) if x is not None)
        text = f"{self.path}: {self.message}" if self.path else self.message
        if self.got is not None:
            text += f" (got {self.got})"
        return f"{where}: {text}" if where else text


class SceneError(ModelError):
    """A scene that cannot be built; ``problems`` lists every problem found, not just the first.

    Attributes:
        problems: Each problem with its path, message, value and line.
        source: The scene file's name, when it came from a file.
    """

    def __init__(self, problems: list[SceneProblem], source: str | None = None) -> None:
        self.problems = problems
        self.source = source
        count = len(problems)
        heading = f"{count} problem{'s' if count != 1 else ''} in the scene"
        lines = [p.describe(source) for p in problems]
        super().__init__("\n".join([heading + ":", *("  " + line for line in lines)]))


class SweepError(ModelError):
    """A sweep that cannot run: its description, or runs whose scenes fail validation.

    Every problem is listed, and nothing has run or been written when it is raised.

    Attributes:
        problems: Each problem with its path (``parameters[1].path``, or ``run 3 (dt=0.5):
            integration.dt`` for a run's scene), message, value and line.
        source: The sweep file's name, when it came from a file.
    """

    def __init__(self, problems: list[SceneProblem], source: str | None = None) -> None:
        self.problems = problems
        self.source = source
        lines = [p.describe(source) for p in problems]
        if len(lines) == 1:  # one problem: one line
            super().__init__(lines[0])
            return
        heading = f"{len(lines)} problems in the sweep"
        super().__init__("\n".join([heading + ":", *("  " + line for line in lines)]))


class SimulationError(VisvivaError, RuntimeError):
    """A run stopped because the numerics failed.

    Attributes:
        t: Simulation time of the failure [s].
        step: Index of the step that failed (0 is the first step; messages count from 1), or
            ``None`` when the failure was raised outside a simulation loop (a direct
            ``Integrator.step`` call).
    """

    def __init__(self, message: str, *, t: float, step: int | None) -> None:
        super().__init__(message)
        self.t = t
        self.step = step


class SimulationDiverged(SimulationError):
    """The state became non-finite or left the divergence limit.

    Attributes:
        component: Name of the first offending state component, e.g. ``"q[3]"`` or
            ``"y[17, 2]"`` (system 17, coordinate 2 of a batch).
        value: Its value when the watch fired (``nan``, ``inf`` or a huge number).
        suggested_dt: The stability advisor's largest stable step for the method, from the
            Jacobian at the last finite state, or ``None`` if it could not be estimated.
        system: The offender's system (row) in a batch, or ``None`` for a single system.
        entry: Where the offender is: the index of its integrated array in the state's parts
            and its flat index in that array (of its row, in a batch), or ``None``.
    """

    def __init__(
        self,
        message: str,
        *,
        t: float,
        step: int | None,
        component: str,
        value: float,
        suggested_dt: float | None,
        system: int | None = None,
        entry: tuple[int, int] | None = None,
    ) -> None:
        super().__init__(message, t=t, step=step)
        self.component = component
        self.value = value
        self.suggested_dt = suggested_dt
        self.system = system
        self.entry = entry


class NewtonConvergenceError(SimulationError):
    """Newton's method did not converge within its iteration cap in an implicit step.

    Attributes:
        iterations: Iterations performed.
        update_norm: Scaled norm of the last Newton update (converged means ≤ 1).
    """

    def __init__(
        self, message: str, *, t: float, step: int | None, iterations: int, update_norm: float
    ) -> None:
        super().__init__(message, t=t, step=step)
        self.iterations = iterations
        self.update_norm = update_norm


class Interrupted(VisvivaError):
    """A run stopped early because the process received SIGINT or SIGTERM (inside a job:
    :class:`~visviva.simulation.interrupt.StopOnSignal`).

    Attributes:
        signal: The signal's name, ``"SIGINT"`` or ``"SIGTERM"``.
        t: Simulation time reached [s] (the last recorded frame).
        recording: The frames recorded up to ``t`` (set by the loop that stopped).
    """

    def __init__(self, signal_name: str, t: float) -> None:
        super().__init__(f"interrupted by {signal_name} at t = {t:.6g} s")
        self.signal = signal_name
        self.t = t
