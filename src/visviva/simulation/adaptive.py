"""The adaptive driver: steps chosen by an error estimate (for ``dopri5``).

Each attempted step estimates its local error ``e``; it is accepted when the scaled norm
``‖e / (atol + rtol·max(|y|, |y'|))‖`` (RMS over the components of a system, worst system of a
batch) is at most 1. The next step is ``h·min(10, max(0.2, 0.9·err^(−1/5)))``, never growing
right after a rejection. The first step, unless given, follows Hairer, Nørsett & Wanner (1993,
§II.4). Frames are the accepted steps, or the requested times ``t_eval`` interpolated with the
method's dense output; ``dense_output=True`` keeps every step's interpolant for
``Solution.sol(t)``.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np

from .._version import __version__
from ..errors import SimulationError
from ..integrators.runge_kutta import initial_rate
from .progress import Progress
from .recorder import FrameRecorder
from .watch import DivergenceWatch

if TYPE_CHECKING:
    from ..integrators.dopri5 import DormandPrince5, Step
    from ..ode.problems import Problem
    from ..ode.state import State
    from .recording import Recording

__all__ = ["DenseOutput", "integrate_adaptive"]

#: Step-size controller: safety factor and bounds on the change of h per step.
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0


class DenseOutput:
    """The continuous solution of an adaptive run: ``sol(t)`` for ``t0 ≤ t ≤ until``.

    Calling it with a scalar time returns the state parts at that time: ``(y,)`` or ``(q, v)``.
    """

    def __init__(self, steps: list[Step]) -> None:
        self._steps = steps
        self._starts = np.array([s.start.t for s in steps])
        self.t_min = steps[0].start.t if steps else np.nan
        self.t_max = steps[-1].end.t if steps else np.nan

    def __call__(self, t: float) -> tuple[np.ndarray, ...]:
        if not self.t_min <= t <= self.t_max:
            raise ValueError(f"t={t!r} is outside the solved interval [{self.t_min}, {self.t_max}]")
        index = max(0, int(np.searchsorted(self._starts, t, side="right")) - 1)
        step = self._steps[index]
        return step.interpolate((t - step.start.t) / step.dt)


def _error_norm(
    error: tuple[np.ndarray, ...],
    before: tuple[np.ndarray, ...],
    after: tuple[np.ndarray, ...],
    rtol: float,
    atol: float,
) -> float:
    """Worst system's RMS of ``error / (atol + rtol·max(|before|, |after|))``."""
    total, count = 0.0, 0
    for e, y0, y1 in zip(error, before, after, strict=True):
        scaled = np.abs(e) / (atol + rtol * np.maximum(np.abs(y0), np.abs(y1)))
        total = total + (scaled * scaled).sum(axis=-1)
        count += e.shape[-1]
    # Array methods rather than np.max/np.einsum: this runs every step on tiny arrays.
    worst = float(np.sqrt(np.asarray(total).max() / count))
    return worst if np.isfinite(worst) else np.inf


def _initial_step(
    method: DormandPrince5, system: Any, state: State, until: float, rtol: float, atol: float
) -> float:
    """Starting step from the sizes of y, f and a finite-difference estimate of f'.

    ``state`` must carry its derivative (see :meth:`FirstOrderState.with_derivative`).
    """
    parts = state.parts
    rates = initial_rate(system, state)

    def norm(values: tuple[np.ndarray, ...]) -> float:
        scaled = [v / (atol + rtol * np.abs(y)) for v, y in zip(values, parts, strict=True)]
        return float(np.max(np.sqrt(np.mean(np.abs(np.concatenate(scaled, -1)) ** 2, -1))))

    d0, d1 = norm(parts), norm(rates)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, until - state.t)
    probe = tuple(y + h0 * r for y, r in zip(parts, rates, strict=True))
    rates1 = system.derivative(state.t + h0, probe)
    d2 = norm(tuple(r1 - r0 for r1, r0 in zip(rates1, rates, strict=True))) / h0
    largest = max(d1, d2)
    exponent = 1.0 / (method.error_estimator_order + 1)
    h1 = max(1e-6, 1e-3 * h0) if largest <= 1e-15 else (0.01 / largest) ** exponent
    return min(100.0 * h0, h1, until - state.t)


def _check_step_size(h: float, t: float, until: float, step: int) -> None:
    """Fail when ``h`` has shrunk to the round-off level of ``t``."""
    if h <= 10.0 * np.spacing(abs(t) + abs(until)):
        raise SimulationError(
            f"the step size became too small ({h:.3g} s) at t={t:.6g} s: the problem is too "
            "stiff for an explicit method at this tolerance, or has a singularity; try "
            "'backward_euler' or 'trapezoidal'",
            t=t,
            step=step,
        )


def integrate_adaptive(
    problem: Problem,
    method: DormandPrince5,
    *,
    until: float,
    rtol: float,
    atol: float,
    first_step: float | None,
    t_eval: np.ndarray | None,
    dense_output: bool,
    max_steps: int,
    progress: bool | None,
    divergence_limit: float | None,
) -> tuple[Recording, DenseOutput | None]:
    """Integrate with error control; arguments as for :func:`visviva.solve` (already checked).

    Raises:
        SimulationError: If the step size underflows, ``max_steps`` is exceeded or the state
            diverges; ``error.recording`` holds the frames so far.
    """
    system = problem.system()
    method.check(system)
    state = problem.initial_state()
    # Evaluate f at the start once; every attempt from here reuses it.
    state = state.with_derivative(system.derivative(state.t, state.parts))
    t0 = state.t
    starts_at_t0 = t_eval is None or t_eval[0] == t0
    recorder = FrameRecorder(system, state, include=starts_at_t0)
    eval_index = 1 if t_eval is not None and starts_at_t0 else 0
    h = (
        first_step
        if first_step is not None
        else (_initial_step(method, system, state, until, rtol, atol) if until > t0 else 0.0)
    )
    watch = DivergenceWatch(system, method, h or 1.0, state, divergence_limit)
    steps: list[Step] = []
    error: SimulationError | None = None
    exponent = -1.0 / (method.error_estimator_order + 1)
    started = time.perf_counter()
    step_index = 0
    with Progress(until - t0, method.name, progress) as bar:
        try:
            while state.t < until:
                if step_index >= max_steps:
                    raise SimulationError(
                        f"reached max_steps={max_steps} at t={state.t:.6g} s before `until` = "
                        f"{until:.6g} s; raise max_steps, loosen rtol/atol, or use an implicit "
                        "method if the problem is stiff",
                        t=state.t,
                        step=step_index,
                    )
                h = min(h, until - state.t)
                _check_step_size(h, state.t, until, step_index)
                rejected = False
                while True:
                    attempt = method.attempt(system, state, h)
                    err = _error_norm(attempt.error, state.parts, attempt.end.parts, rtol, atol)
                    if err <= 1.0:
                        break
                    system.counters.rejected_steps += 1
                    rejected = True
                    h *= max(MIN_FACTOR, SAFETY * err**exponent) if np.isfinite(err) else MIN_FACTOR
                    _check_step_size(h, state.t, until, step_index)
                end = attempt.end
                if until - end.t <= 10.0 * np.spacing(abs(until)):
                    end = end.at_time(until)
                if not watch.healthy(end):
                    raise watch.diverged(end, step_index, state)
                system.counters.accepted_steps += 1
                step_index += 1
                if t_eval is None:
                    recorder.append(end)
                else:
                    while eval_index < t_eval.size and t_eval[eval_index] <= end.t:
                        theta = (t_eval[eval_index] - state.t) / attempt.dt
                        values = attempt.interpolate(theta)
                        recorder.append(state.from_parts(float(t_eval[eval_index]), values))
                        eval_index += 1
                if dense_output:
                    steps.append(attempt)
                factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err**exponent)
                h *= min(1.0, factor) if rejected else factor
                bar.advance(end.t - state.t)
                state = end
        except SimulationError as failure:
            error = failure
    attrs: dict[str, Any] = {
        "method": method.name,
        "adaptive": True,
        "compiled": False,
        "rtol": rtol,
        "atol": atol,
        "t0": t0,
        "until": until,
        "problem": problem.name,
        "kind": problem.kind,
        "conservative": problem.conservative,
        "batch_size": problem.batch_size,
        "visviva_version": __version__,
        "wall_time_s": time.perf_counter() - started,
        "steps": system.counters.accepted_steps,
        **system.counters.as_dict(),
        "success": error is None,
        "message": "completed" if error is None else str(error),
    }
    recording = recorder.recording(attrs)
    if error is not None:
        error.recording = recording
        raise error
    return recording, (DenseOutput(steps) if dense_output else None)
