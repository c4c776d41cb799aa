"""``vv.solve``: integrate a problem with any registered method and get a :class:`Solution`.

``solve`` is the one function that runs a problem (it was ``solve`` and ``simulate``; the latter
is gone: ``vv.solve(...).recording`` is the recording it returned, and
``vv.solve(...).raise_for_status()`` raises the error it raised). Fixed-step methods run through
the one simulation loop (:func:`~visviva.simulation.loop.run_fixed_steps`); adaptive ones
(``dopri5``) through the adaptive driver unless ``adaptive=False``. A numerical failure does
not raise here: the solution reports ``success=False`` with a message and keeps the frames
computed before it (call :meth:`Solution.raise_for_status` to turn that into the exception).
Invalid arguments always raise :class:`~visviva.errors.ModelError` before any step.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .._compiling import watch_compiles
from .._validation import describe, real_number, whole_number
from ..errors import ModelError, SimulationError
from ..integrators import Integrator, get, names
from .adaptive import DenseOutput, integrate_adaptive
from .loop import check_end_time, check_problem, run_fixed_steps

if TYPE_CHECKING:
    from ..ode.problems import Problem
    from .recording import Recording

__all__ = ["Solution", "solve"]


@dataclass(frozen=True)
class Solution:
    """The result of :func:`solve`.

    Attributes:
        recording: The frames (times, state arrays, energy) and run attributes.
        success: False if the run stopped early (divergence, Newton failure, step underflow).
        message: ``"completed"`` or the reason it stopped.
        error: The exception that stopped the run, if any.
        sol: With ``dense_output=True`` (adaptive methods), the continuous solution
            ``sol(t) -> (y,)`` or ``(q, v)``; else ``None``.
    """

    recording: Recording
    success: bool
    message: str
    error: SimulationError | None = None
    sol: DenseOutput | None = None

    @property
    def t(self) -> np.ndarray:
        """Frame times [s], shape ``(frames,)``."""
        return self.recording.time

    @property
    def y(self) -> np.ndarray:
        """States of a first-order problem, ``(frames, n)`` or ``(frames, batch, n)``."""
        return self._field("y")

    @property
    def q(self) -> np.ndarray:
        """Coordinates of a second-order problem, ``(frames, n)`` or ``(frames, batch, n)``."""
        return self._field("q")

    @property
    def v(self) -> np.ndarray:
        """Velocities of a second-order problem, shape of :attr:`q`."""
        return self._field("v")

    @property
    def energy(self) -> np.ndarray:
        """The problem's energy at every frame, ``(frames,)`` or ``(frames, batch)``."""
        return self._field("energy")

    @property
    def method(self) -> str:
        """Name of the integrator used."""
        return str(self.recording.attrs["method"])

    @property
    def counters(self) -> dict[str, int]:
        """Work done: f-evaluations, Jacobians, linear solves, Newton iterations, steps."""
        keys = (
            "f_evaluations",
            "jacobian_evaluations",
            "linear_solves",
            "newton_iterations",
            "accepted_steps",
            "rejected_steps",
        )
        return {k: int(self.recording.attrs[k]) for k in keys}

    def _field(self, name: str) -> np.ndarray:
        if name not in self.recording:
            raise AttributeError(
                f"this solution has no {name!r}; it has: {', '.join(self.recording.fields)}"
            )
        return self.recording[name]

    def raise_for_status(self) -> Solution:
        """Raise the run's error if it failed; return the solution otherwise (for chaining)."""
        if self.error is not None:
            raise self.error
        return self


def solve(
    problem: Problem,
    method: str | Integrator = "rk4",
    *,
    until: float,
    dt: float | None = None,
    record_every: int = 1,
    substeps: int = 1,
    adaptive: bool | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    t_eval: Any = None,
    dense_output: bool = False,
    max_steps: int = 1_000_000,
    progress: bool | None = None,
    divergence_limit: float | None = None,
    compiled: bool | None = None,
) -> Solution:
    """Integrate ``problem`` from its ``t0`` to the time ``until`` (an absolute time: the run
    lasts ``until − t0``).

    Args:
        problem: A :class:`~visviva.ode.FirstOrderProblem` or
            :class:`~visviva.ode.SecondOrderProblem`.
        method: Integrator name (``vv.integrators.names()``) or instance.
        until: End time [s], not before ``problem.t0``.
        dt: Step [s] for fixed-step methods (required); for adaptive ones, the first step
            (chosen automatically if omitted).
        record_every: Fixed-step methods: record every k-th step (first and last always).
        substeps: Fixed-step methods: integrator steps per ``dt``.
        adaptive: Use error control; default: if the method supports it.
        rtol, atol: Adaptive methods: relative and absolute local error tolerances (defaults
            1e-6 and 1e-9).
        t_eval: Adaptive methods: times at which to record (interpolated); default: every step.
        dense_output: Adaptive methods: keep the continuous solution in ``Solution.sol``.
        max_steps: Adaptive methods: give up after this many accepted steps.
        progress: Progress bar on long runs (default: only when stderr is a terminal).
        divergence_limit: Largest allowed ``|component|`` before the run counts as diverged
            (default ``1e10 × max(1, max |initial state|)``).
        compiled: Fixed-step methods: ``None`` compiles the whole loop when the problem's
            functions are Numba functions, ``False`` never, ``True`` requires it.

    Returns:
        A :class:`Solution`: its ``recording`` holds the frames; a numerical failure is
        reported in it (``success=False``), and :meth:`Solution.raise_for_status` raises it.

    Raises:
        ModelError: For invalid arguments, before any step.

    Example:
        >>> import visviva as vv
        >>> spring = vv.ode.SecondOrderProblem(lambda t, q: -q, q0=[1.0], v0=[0.0])
        >>> sol = vv.solve(spring, "symplectic_euler", dt=0.1, until=10.0, record_every=10)
        >>> sol.success, sol.q.shape, sol.counters["f_evaluations"]
        (True, (11, 1), 100)
    """
    watch_compiles()  # the first solve of a problem may compile for a while: say so
    check_problem(problem)
    integrator = get(method)
    use_adaptive = integrator.adaptive if adaptive is None else bool(adaptive)
    if use_adaptive and not integrator.adaptive:
        raise ModelError(
            f"method {integrator.name!r} has no error control; adaptive methods: "
            + ", ".join(n for n in names() if get(n).adaptive)
        )
    until = check_end_time(problem, until)
    try:
        if use_adaptive:
            return _solve_adaptive(
                problem,
                integrator,
                until,
                dt,
                rtol,
                atol,
                t_eval,
                dense_output,
                max_steps,
                progress,
                divergence_limit,
                record_every,
                substeps,
                compiled,
            )
        for name, value in (("rtol", rtol), ("atol", atol), ("t_eval", t_eval)):
            if value is not None:
                raise ModelError(
                    f"`{name}` applies to adaptive methods only; {integrator.name!r} takes "
                    "fixed steps of `dt`"
                )
        if dense_output:
            raise ModelError("`dense_output` applies to adaptive methods only")
        if dt is None:
            raise ModelError(f"`dt` is required for the fixed-step method {integrator.name!r}")
        recording = run_fixed_steps(
            problem,
            integrator,
            dt=dt,
            until=until,
            substeps=substeps,
            record_every=record_every,
            progress=progress,
            divergence_limit=divergence_limit,
            compiled=compiled,
        )
        return Solution(recording, True, "completed")
    except SimulationError as failure:
        return Solution(failure.recording, False, str(failure), failure)


def _solve_adaptive(
    problem: Problem,
    integrator: Integrator,
    until: float,
    dt: float | None,
    rtol: float | None,
    atol: float | None,
    t_eval: Any,
    dense_output: bool,
    max_steps: int,
    progress: bool | None,
    divergence_limit: float | None,
    record_every: int,
    substeps: int,
    compiled: bool | None,
) -> Solution:
    if record_every != 1 or substeps != 1:
        raise ModelError("`record_every` and `substeps` apply to fixed-step runs; use `t_eval`")
    if compiled:
        raise ModelError(
            f"compiled=True applies to fixed-step explicit methods; {integrator.name!r} runs "
            "adaptively here (pass adaptive=False for fixed steps)"
        )
    rtol = 1e-6 if rtol is None else real_number("rtol", rtol, positive=True)
    atol = 1e-9 if atol is None else real_number("atol", atol, nonnegative=True)
    if atol == 0.0:
        raise ModelError(
            "`atol` must be positive (got 0.0): a component at or through zero has no relative "
            "error scale, so the step would shrink without end; use e.g. atol=1e-12 (state units)"
        )
    first_step = None if dt is None else real_number("dt", dt, positive=True, unit=" s")
    max_steps = whole_number("max_steps", max_steps, minimum=1)
    if divergence_limit is not None:
        divergence_limit = real_number("divergence_limit", divergence_limit, positive=True)
    times = None if t_eval is None else _check_times(t_eval, problem.t0, until)
    recording, dense = integrate_adaptive(
        problem,
        integrator,  # type: ignore[arg-type]
        until=until,
        rtol=rtol,
        atol=atol,
        first_step=first_step,
        t_eval=times,
        dense_output=dense_output,
        max_steps=max_steps,
        progress=progress,
        divergence_limit=divergence_limit,
    )
    return Solution(recording, True, "completed", sol=dense)


def _check_times(t_eval: Any, t0: float, until: float) -> np.ndarray:
    """``t_eval`` as a strictly increasing float array within ``[t0, until]``."""
    try:
        times = np.asarray(t_eval, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise ModelError(f"`t_eval` must be an array of times (got {describe(t_eval)})") from None
    if times.size == 0:
        raise ModelError("`t_eval` must not be empty")
    bad = ~np.isfinite(times)
    if bad.any():
        i = int(np.argmax(bad))
        raise ModelError(f"`t_eval` must be finite; entry {i} is {describe(times[i])}")
    steps = np.diff(times)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0)) + 1
        raise ModelError(
            f"`t_eval` must be strictly increasing; entry {i} ({describe(times[i])}) follows "
            f"{describe(times[i - 1])}"
        )
    if times[0] < t0 or times[-1] > until:
        raise ModelError(
            f"`t_eval` must lie within [t0, until] = [{describe(t0)}, {describe(until)}] "
            f"(got [{describe(times[0])}, {describe(times[-1])}])"
        )
    return times
