"""Dormand–Prince 5(4): adaptive explicit Runge–Kutta with error control and dense output.

Seven stages, of which the last is evaluated at the new state and reused as the first stage of
the next step ("first same as last"), so a step costs six evaluations. The fifth-order solution
is propagated; the difference to the embedded fourth-order one estimates the local error, which
the adaptive driver (:mod:`visviva.simulation.adaptive`) keeps below ``atol + rtol·|y|``.
Between steps, a fourth-order continuous extension (Shampine's coefficients as arranged by
Hairer) gives the solution at any time without further evaluations.

``step`` alone is a plain fixed-step fifth-order method (``vv.solve(..., adaptive=False)``).

References:
    J. R. Dormand, P. J. Prince, J. Comput. Appl. Math. 6 (1980) 19-26;
    L. F. Shampine, Math. Comp. 46 (1986) 135-150;
    Hairer, Nørsett & Wanner 1993, §II.4-II.6 (code DOPRI5).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .base import Integrator
from .runge_kutta import ButcherTableau, Stages, initial_rate

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.system import System

__all__ = ["DormandPrince5", "Step"]

_TABLEAU = ButcherTableau(
    [
        [0, 0, 0, 0, 0, 0, 0],
        [1 / 5, 0, 0, 0, 0, 0, 0],
        [3 / 40, 9 / 40, 0, 0, 0, 0, 0],
        [44 / 45, -56 / 15, 32 / 9, 0, 0, 0, 0],
        [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0, 0, 0],
        [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0, 0],
        [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0],
    ],
    [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0],
    [0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1, 1],
)
#: Fifth- minus fourth-order weights: ``h Σ e_i k_i`` estimates the local error.
_ERROR_WEIGHTS = np.array(
    [71 / 57600, 0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40]
)
#: Weights of the fourth-order continuous extension's highest term (Shampine 1986).
_DENSE_WEIGHTS = np.array(
    [
        -12715105075 / 11282082432,
        0,
        87487479700 / 32700410799,
        -10690763975 / 1880347072,
        701980252875 / 199316789632,
        -1453857185 / 822651844,
        69997945 / 29380423,
    ]
)


class Step:
    """One attempted Dormand–Prince step: its result, error estimate and interpolant.

    Attributes:
        start: State at the beginning of the step.
        end: Fifth-order state at the end, with the end-point rate cached.
        error: Estimated local error, one array per state part.
        dt: Step size [s].
    """

    def __init__(self, start: State, end: State, stages: Stages, dt: float) -> None:
        self.start = start
        self.end = end
        self.dt = dt
        self.error = stages.weighted(dt, _ERROR_WEIGHTS)
        self._stages = stages

    def interpolate(self, theta: float) -> tuple[np.ndarray, ...]:
        """State parts at ``start.t + theta·dt`` for ``0 ≤ theta ≤ 1``."""
        h = self.dt
        first, last = self._stages[0], self._stages[-1]
        highest = self._stages.weighted(h, _DENSE_WEIGHTS)
        parts = []
        for p, (y0, y1) in enumerate(zip(self.start.parts, self.end.parts, strict=True)):
            difference = y1 - y0
            slope_gap = h * first[p] - difference
            curvature = difference - h * last[p] - slope_gap
            inner = slope_gap + theta * (curvature + (1.0 - theta) * highest[p])
            parts.append(y0 + theta * (difference + (1.0 - theta) * inner))
        return tuple(parts)


class DormandPrince5(Integrator):
    """Dormand–Prince 5(4), adaptive with dense output (as SciPy's ``RK45``).

    Fifth order; with ``adaptive=False`` a plain fixed-step fifth-order method.
    """

    #: Stages combine derivatives, and ``q'`` is the system's (rigid bodies included).
    manifold_positions = True

    name = "dopri5"
    order = 5
    adaptive = True
    evaluations_per_step = 6
    cost = "6 f-evaluations (first same as last)"
    reference = "Dormand & Prince 1980; Shampine 1986; Hairer, Norsett & Wanner 1993, II.5"
    summary = "Dormand-Prince 5(4): adaptive, error-controlled, dense output"
    tableau = _TABLEAU
    #: Order of the embedded error estimate, which sets the step-size controller's exponent.
    error_estimator_order = 4

    def attempt(self, system: System, state: State, dt: float) -> Step:
        """One step of size ``dt`` with its error estimate (the adaptive driver decides)."""
        tableau = self.tableau
        y0 = state.parts
        stages = Stages(y0, tableau.stages)
        stages.append(initial_rate(system, state))
        for i in range(1, tableau.stages - 1):
            stage = stages.combine(y0, dt, tableau.a[i, :i])
            stages.append(system.derivative(state.t + tableau.c[i] * dt, stage))
        # b_7 = 0: the seventh stage (the rate at the new state) only serves the next step.
        y1 = stages.combine(y0, dt, tableau.b[:-1])
        t1 = state.t + dt
        last = system.derivative(t1, y1)
        stages.append(last)
        end = state.from_parts(t1, y1).with_derivative(last)
        return Step(state, end, stages, dt)

    def step(self, system: System, state: State, dt: float) -> State:
        return self.attempt(system, state, dt).end

    def stability_function(self, z: Any) -> np.ndarray:
        return self.tableau.stability_function(z)
