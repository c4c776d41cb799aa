"""Sensitivity to initial conditions: how fast nearby trajectories separate.

Chaos (seed 001's double pendulum: "perturb input, wild changes to output") means that the
distance between two trajectories that start ``δ0`` apart grows like ``δ0 e^{λ t}`` with a
positive largest Lyapunov exponent ``λ``. :func:`lyapunov_exponent` estimates ``λ`` over a finite
time by Benettin's method (Benettin, Galgani, Giorgilli & Strelcyn 1980): follow a reference
and a companion trajectory, and every ``interval`` seconds add ``log(δ/δ0)`` to a running sum and
pull the companion back to distance ``δ0`` along the current separation, so the separation
stays small (linear) however long the run. The distance is measured in the state ``(q, q̇)``
with each coordinate in its own unit: the exponent does not depend on that choice, the
prefactor does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validation import real_number, state_array
from ..errors import ModelError
from ..simulation.solve import solve
from .lagrangian import LagrangianSystem

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


def _start(system: LagrangianSystem, q0: Any, v0: Any) -> tuple[np.ndarray, np.ndarray]:
    q0, v0 = state_array("q0", q0), state_array("v0", v0)
    if q0.shape != (system.size,) or v0.shape != (system.size,):
        raise ModelError(
            f"`q0` and `v0` must each be one state of {system.size} values "
            f"(got shapes {q0.shape}, {v0.shape})"
        )
    return q0, v0


def separation(
    system: LagrangianSystem,
    q0: Any,
    v0: Any,
    *,
    delta: float = 1e-9,
    t_end: float,
    dt: float,
    method: str = "rk4",
) -> tuple[np.ndarray, np.ndarray]:
    """Distance in ``(q, q̇)`` between the trajectory from ``(q0, v0)`` and one from ``q0 + δ``.

    Both run together as a batch of two. The first coordinate is displaced by ``delta``.

    Returns:
        ``(t, distance)``: the recorded times [s] and the distances, shape ``(frames,)`` each.
    """
    q0, v0 = _start(system, q0, v0)
    delta = real_number("delta", delta, positive=True)
    displaced = q0.copy()
    displaced[0] += delta
    problem = system.problem(np.stack([q0, displaced]), np.stack([v0, v0]))
    solution = solve(problem, method, dt=dt, t_end=t_end).raise_for_status()
    difference = np.concatenate(
        [solution.q[:, 1] - solution.q[:, 0], solution.v[:, 1] - solution.v[:, 0]], axis=-1
    )
    return solution.t, np.linalg.norm(difference, axis=-1)


def lyapunov_exponent(
    system: LagrangianSystem,
    q0: Any,
    v0: Any,
    *,
    t_end: float,
    dt: float,
    interval: float = 1.0,
    delta: float = 1e-8,
    method: str = "rk4",
) -> LyapunovEstimate:
    """Estimate the largest Lyapunov exponent [1/s] from ``(q0, v0)`` over ``t_end`` seconds.

    Args:
        system: The system.
        q0, v0: The reference trajectory's start, one state of ``n`` values each.
        t_end: Length of the estimate [s]; the result is a finite-time exponent.
        dt: Integration step [s] (a whole number of steps per ``interval``).
        interval: Renormalisation period [s]: short enough that ``δ0 e^{λ·interval}`` stays
            well below the size of the attractor.
        delta: Separation ``δ0`` kept between the trajectories (in state units).
        method: Integrator.
    """
    q, v = _start(system, q0, v0)
    interval = real_number("interval", interval, positive=True, unit=" s")
    delta = real_number("delta", delta, positive=True)
    t_end = real_number("t_end", t_end, positive=True, unit=" s")
    count = round(t_end / interval)
    if count < 1:
        raise ModelError(f"`t_end` ({t_end} s) must cover at least one `interval` ({interval} s)")
    steps = max(1, round(interval / real_number("dt", dt, positive=True, unit=" s")))
    n = system.size
    direction = np.zeros(2 * n)
    direction[0] = 1.0
    reference = np.concatenate([q, v])
    companion = reference + delta * direction
    growth = np.empty(count)
    time = 0.0
    for k in range(count):
        states = np.stack([reference, companion])
        problem = system.problem(states[:, :n], states[:, n:], time)
        final = solve(
            problem, method, dt=dt, t_end=time + interval, record_every=steps
        ).raise_for_status()
        reference = np.concatenate([final.q[-1, 0], final.v[-1, 0]])
        offset = np.concatenate([final.q[-1, 1], final.v[-1, 1]]) - reference
        distance = float(np.linalg.norm(offset))
        if not np.isfinite(distance) or distance == 0.0:
            raise ModelError(
                f"the companion trajectory's separation became {distance} at t = {time:.6g} s; "
                "choose a larger `delta` or a smaller `interval`"
            )
        growth[k] = np.log(distance / delta)
        companion = reference + offset * (delta / distance)
        time += interval
    times = interval * np.arange(1, count + 1)
    running = np.cumsum(growth) / times
    return LyapunovEstimate(float(running[-1]), times, running, growth)
