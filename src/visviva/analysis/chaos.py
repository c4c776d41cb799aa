"""Sensitivity to initial conditions: how fast nearby trajectories separate.

Chaos (seed 001's double pendulum: "perturb input, wild changes to output") means that the
distance between two trajectories that start ``δ0`` apart grows like ``δ0 e^{λ t}`` with a
positive largest Lyapunov exponent ``λ``. :func:`lyapunov_exponent` estimates ``λ`` over a finite
time by Benettin's method (Benettin, Galgani, Giorgilli & Strelcyn 1980): follow a reference
and a companion trajectory, and every ``interval`` seconds add ``log(δ/δ0)`` to a running sum and
pull the companion back to distance ``δ0`` along the current separation, so the separation
stays small (linear) however long the run.

Both measures take any problem of one system — a Lagrangian system's, a scene's, one written by
hand — and advance its state with a registered integrator's ``step``. The distance is measured
in the integrated arrays, ``(q, q̇)`` or ``y``, with each entry in its own unit: the exponent does
not depend on that choice, the prefactor does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._validation import real_number
from ..errors import ModelError, SimulationError
from ..integrators import Integrator, get

if TYPE_CHECKING:
    from ..ode.problems import Problem
    from ..ode.state import State
    from ..ode.system import System

__all__ = ["LyapunovEstimate", "lyapunov_exponent", "separation"]


@dataclass(frozen=True)
class LyapunovEstimate:
    """The result of :func:`lyapunov_exponent`.

    Attributes:
        exponent: The finite-time estimate of the largest Lyapunov exponent ``λ`` [1/s].
        times: End of each renormalisation interval [s], shape ``(k,)``.
        running: The estimate using the intervals up to each time [1/s], shape ``(k,)``: it
            settles as ``t`` grows (and tends to 0 like ``log(·)/t`` for regular motion).
        growth: ``log(δ/δ0)`` over each interval, shape ``(k,)``.
    """

    exponent: float
    times: np.ndarray
    running: np.ndarray
    growth: np.ndarray


def separation(
    problem: Problem,
    *,
    delta: float = 1e-9,
    until: float,
    dt: float,
    method: str | Integrator = "rk4",
) -> tuple[np.ndarray, np.ndarray]:
    """Distance between the trajectory from ``problem``'s initial state and one started ``δ``
    away from it, at every step.

    The companion's first integrated entry (``q[0]`` or ``y[0]``) is displaced by ``delta``.

    Args:
        problem: One system (not a batch); its initial state starts the reference trajectory.
        delta: Initial separation, in the unit of that first entry.
        until: End of the run [s].
        dt: Step [s], rounded so that a whole number of steps ends at ``until``.
        method: Integrator name or instance.

    Returns:
        ``(t, distance)``: the times [s] and the distances in the integrated arrays, shape
        ``(steps + 1,)`` each.

    Raises:
        SimulationError: If either trajectory stops being finite.
    """
    system, reference, integrator = _start(problem, method)
    delta = real_number("delta", delta, positive=True)
    steps, h = _steps(real_number("until", until, unit=" s") - problem.t0, dt, "until")
    companion = _displaced(reference, delta)
    times = problem.t0 + h * np.arange(steps + 1)
    distance = np.empty(steps + 1)
    distance[0] = delta
    for k in range(1, steps + 1):
        reference = integrator.step(system, reference, h)
        companion = integrator.step(system, companion, h)
        with np.errstate(over="ignore", invalid="ignore"):  # a blow-up is reported below
            distance[k] = np.linalg.norm(_flat(companion) - _flat(reference))
        if not np.isfinite(distance[k]):
            raise _diverged(times[k], k - 1, integrator, h)
    return times, distance


def lyapunov_exponent(
    problem: Problem,
    *,
    until: float,
    dt: float,
    interval: float = 1.0,
    delta: float = 1e-8,
    method: str | Integrator = "rk4",
) -> LyapunovEstimate:
    """Estimate the largest Lyapunov exponent [1/s] from ``problem``'s initial state.

    Args:
        problem: One system (not a batch); its initial state starts the reference trajectory.
        until: End of the estimate [s]; the result is a finite-time exponent over
            ``[t0, until]``, rounded to a whole number of intervals.
        dt: Integration step [s], rounded so that a whole number of steps fills an interval.
        interval: Renormalisation period [s]: short enough that ``δ0 e^{λ·interval}`` stays
            well below the size of the attractor.
        delta: Separation ``δ0`` kept between the trajectories (in state units).
        method: Integrator name or instance.

    Raises:
        ModelError: For bad arguments, or a ``delta`` so small that the separation vanishes.
        SimulationError: If either trajectory stops being finite.
    """
    system, reference, integrator = _start(problem, method)
    interval = real_number("interval", interval, positive=True, unit=" s")
    delta = real_number("delta", delta, positive=True)
    span = real_number("until", until, unit=" s") - problem.t0
    count = round(span / interval)
    if count < 1:
        raise ModelError(
            f"`until` ({until} s) must be at least one `interval` ({interval} s) after the "
            f"problem's t0 ({problem.t0} s)"
        )
    steps, h = _steps(interval, dt, "interval")
    companion = _displaced(reference, delta)
    growth = np.empty(count)
    for k in range(count):
        for _ in range(steps):
            reference = integrator.step(system, reference, h)
            companion = integrator.step(system, companion, h)
        end = problem.t0 + (k + 1) * interval  # from the counter, not a sum of steps
        reference = reference.at_time(end)
        with np.errstate(over="ignore", invalid="ignore"):  # a blow-up is reported below
            offset = _flat(companion) - _flat(reference)
            distance = float(np.linalg.norm(offset))
        if not np.isfinite(distance):
            raise _diverged(end, (k + 1) * steps - 1, integrator, h)
        if distance == 0.0:
            raise ModelError(
                f"the companion trajectory's separation vanished at t = {end:.6g} s; "
                "choose a larger `delta`"
            )
        growth[k] = np.log(distance / delta)
        companion = _replaced(reference, _flat(reference) + offset * (delta / distance))
    elapsed = interval * np.arange(1, count + 1)
    running = np.cumsum(growth) / elapsed
    return LyapunovEstimate(float(running[-1]), problem.t0 + elapsed, running, growth)


def _start(problem: Problem, method: str | Integrator) -> tuple[System, State, Integrator]:
    """The system to step, its initial state and the integrator, checked."""
    if problem.batch_size is not None:
        raise ModelError(
            f"the problem must be one system, not a batch of {problem.batch_size}: the measure "
            "runs its own companion trajectory beside it"
        )
    integrator = get(method)
    system = problem.system()
    integrator.check(system)
    return system, problem.initial_state(), integrator


def _steps(span: float, dt: float, name: str) -> tuple[int, float]:
    """The whole number of steps of about ``dt`` that fill ``span``, and their length."""
    dt = real_number("dt", dt, positive=True, unit=" s")
    if not span > 0.0:
        raise ModelError(f"`{name}` must leave a positive time to integrate (got a span of {span})")
    steps = max(1, round(span / dt))
    return steps, span / steps


def _flat(state: State) -> np.ndarray:
    """The integrated arrays of ``state`` as one vector: ``(q, v)`` or ``y``."""
    return np.concatenate([part.ravel() for part in state.parts])


def _replaced(state: State, vector: np.ndarray) -> State:
    """``state`` with its integrated arrays taken from ``vector`` (the inverse of _flat)."""
    parts, start = [], 0
    for part in state.parts:
        parts.append(vector[start : start + part.size].reshape(part.shape))
        start += part.size
    return state.from_parts(state.t, tuple(parts))


def _displaced(state: State, delta: float) -> State:
    """``state`` with its first integrated entry moved by ``delta``."""
    vector = _flat(state)
    vector[0] += delta
    return _replaced(state, vector)


def _diverged(t: float, step: int, integrator: Integrator, h: float) -> SimulationError:
    return SimulationError(
        f"the trajectories stopped being finite at t = {t:.6g} s; the step {h:.3g} s may be "
        f"too large for {integrator.name!r}: choose a smaller `dt`",
        t=float(t),
        step=step,
    )
