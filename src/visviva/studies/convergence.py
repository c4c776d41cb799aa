"""Empirical order of accuracy: error against step size on a log–log scale.

A method of order ``p`` has global error ``≈ C·dt^p`` at a fixed time once ``dt`` is small
enough (seed 000: "halving Δt should reduce the error by a factor of 2" for a first-order
method). :func:`convergence_order` runs a method at successively halved steps, measures the
error at ``until`` against a reference solution, and fits the slope over the *asymptotic range*:
points above the round-off floor whose local slopes agree, found by starting from the finest
steps and adding coarser ones while they stay on the same line.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import describe, real_number, whole_number
from ..errors import ModelError
from ..integrators import Integrator, get
from ..simulation.solution import solve

if TYPE_CHECKING:
    from ..ode.problems import Problem

__all__ = ["ConvergenceStudy", "convergence_order"]

#: Errors below this fraction of the solution's size are round-off, not truncation.
ROUND_OFF_FLOOR = 1e-12
#: Largest change of the local slope still counted as the same asymptotic line.
SLOPE_AGREEMENT = 0.15


@dataclass(frozen=True)
class ConvergenceStudy:
    """Errors of one method at a sequence of step sizes, and the fitted order.

    Attributes:
        method: Method name.
        declared_order: The order the method declares.
        dt: Step sizes [s], decreasing.
        error: Max-norm error at ``until`` for each step size.
        used: Mask of the points in the asymptotic fit.
        order: Fitted slope of ``log(error)`` against ``log(dt)`` (``nan`` if fewer than three
            points are usable).
        constant: Fitted ``C`` in ``error ≈ C·dt^order``.
    """

    method: str
    declared_order: int
    dt: np.ndarray
    error: np.ndarray
    used: np.ndarray
    order: float
    constant: float

    def local_orders(self) -> np.ndarray:
        """Slopes between consecutive step sizes, shape ``(len(dt) − 1,)``."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.log(self.error[:-1] / self.error[1:]) / np.log(self.dt[:-1] / self.dt[1:])


def _reference_parts(reference: Any, problem: Problem, until: float) -> tuple[np.ndarray, ...]:
    value = reference(until) if callable(reference) else reference
    parts = (
        tuple(np.asarray(v) for v in value) if isinstance(value, tuple) else (np.asarray(value),)
    )
    names = problem.initial_state().names()
    if len(parts) != len(names):
        shown = names[0] if len(names) == 1 else f"({', '.join(names)})"
        raise ModelError(f"`reference` must give {shown} at `until` for this problem")
    return parts


def convergence_order(
    problem: Problem,
    method: str | Integrator,
    *,
    until: float,
    dt: Sequence[float] | None = None,
    reference: Callable[[float], Any] | Any = None,
    levels: int = 8,
) -> ConvergenceStudy:
    """Measure the order of accuracy of ``method`` on ``problem``.

    Args:
        problem: The problem to integrate.
        method: Method name or instance (adaptive methods run with fixed steps here).
        until: Time at which the error is measured [s].
        dt: Step sizes to try; default ``(until − t0)/8`` halved ``levels − 1`` times.
        reference: The exact solution at ``until``: a callable ``reference(t)`` or the value,
            ``y`` or ``(q, v)``. Default: a Dormand–Prince solution at ``rtol = 1e-13``, which
            limits the measurable error to about 1e-10.
        levels: Number of step sizes when ``dt`` is not given (at least 3).

    Returns:
        A :class:`ConvergenceStudy`.

    Example:
        >>> import numpy as np, visviva as vv
        >>> decay = vv.ode.FirstOrderProblem(lambda t, y: -y, [1.0])
        >>> study = vv.studies.convergence_order(decay, "heun", until=1.0,
        ...                                       reference=lambda t: np.exp(-t))
        >>> round(study.order, 1)
        2.0
    """

    integrator = get(method)
    until = real_number("until", until, unit=" s")
    span = until - problem.t0
    if not span > 0:
        raise ModelError(f"`until` must be after t0 (got until={until!r}, t0={problem.t0!r})")
    if dt is None:
        levels = whole_number("levels", levels, minimum=3)
        steps = np.array([span / (8 * 2**k) for k in range(levels)], dtype=np.float64)
    else:
        steps = np.sort(np.asarray(dt, dtype=np.float64).ravel())[::-1]
        if steps.size < 3 or not np.all(np.isfinite(steps)) or steps[-1] <= 0:
            raise ModelError(
                f"`dt` must hold at least three positive finite step sizes (got {describe(dt)})"
            )
    floor_scale = 1.0
    names = problem.initial_state().names()
    if reference is None:
        accurate = solve(problem, "dopri5", until=until, rtol=1e-13, atol=1e-13).raise_for_status()
        exact = tuple(accurate.recording[name][-1] for name in names)
        floor_scale = 1000.0  # the reference itself is only good to ~1e-11
    else:
        exact = _reference_parts(reference, problem, until)
    scale = max(1.0, max(float(np.max(np.abs(p))) for p in exact))
    errors = np.empty(steps.size)
    for i, h in enumerate(steps):
        solution = solve(
            problem, integrator, until=until, dt=float(h), adaptive=False, record_every=10**9
        )
        if not solution.success:
            errors[i] = np.inf
            continue
        final = tuple(solution.recording[name][-1] for name in names)
        errors[i] = max(float(np.max(np.abs(f - e))) for f, e in zip(final, exact, strict=True))
    used = _asymptotic_range(steps, errors, ROUND_OFF_FLOOR * floor_scale * scale)
    if used.sum() >= 3:
        slope, intercept = np.polyfit(np.log(steps[used]), np.log(errors[used]), 1)
        order, constant = float(slope), float(np.exp(intercept))
    else:
        order, constant = float("nan"), float("nan")
    return ConvergenceStudy(integrator.name, integrator.order, steps, errors, used, order, constant)


def _asymptotic_range(dt: np.ndarray, error: np.ndarray, floor: float) -> np.ndarray:
    """Mask of the finest run of consecutive points above ``floor`` on one straight line."""
    valid = np.isfinite(error) & (error > floor)
    used = np.zeros(dt.size, dtype=bool)
    indices = np.flatnonzero(valid)
    if indices.size < 2:
        return used
    # Finest usable point, then walk towards coarser steps while the slope stays put.
    finest = indices[-1]
    start = finest
    slopes: list[float] = []
    while start - 1 >= 0 and valid[start - 1]:
        slope = np.log(error[start - 1] / error[start]) / np.log(dt[start - 1] / dt[start])
        if slopes and abs(slope - slopes[0]) > SLOPE_AGREEMENT:
            break
        slopes.append(float(slope))
        start -= 1
    used[start : finest + 1] = True
    return used
