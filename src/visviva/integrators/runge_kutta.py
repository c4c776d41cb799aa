"""Explicit Runge–Kutta methods: explicit Euler, midpoint (RK2), Heun and the classic RK4.

Each method is data — a Butcher tableau ``(A, b, c)`` — on a small class, as in SciPy's
``integrate._ivp.rk``; one generic step serves them all, on first-order states ``(y,)`` and on
split second-order states ``(q, v)`` alike (``q' = v``, ``v' = a``). Stage ``i`` evaluates
``k_i = f(t + c_i h, y + h Σ_j a_ij k_j)`` and the step returns ``y + h Σ_i b_i k_i``
(seed 002's RK4 with ``k_i`` scaled by ``h``). The stability function follows from the tableau,
``R(z) = 1 + z bᵀ (I − zA)⁻¹ 𝟙``, a polynomial of degree ``s`` for an explicit method.

References:
    J. C. Butcher, *Numerical Methods for Ordinary Differential Equations*, 3rd ed., Wiley 2016.
    E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*, 2nd ed.,
    Springer 1993, §II.1.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from .base import CompiledStep, Integrator

if TYPE_CHECKING:
    from ..ode.problems import Problem
    from ..ode.state import State
    from ..ode.system import System

__all__ = [
    "ButcherTableau",
    "ExplicitEuler",
    "ExplicitRungeKutta",
    "Heun",
    "Midpoint",
    "RungeKutta4",
    "Stages",
]

#: Tolerance of the tableau consistency checks (row sums of A equal c, weights sum to 1).
TABLEAU_TOLERANCE = 1e-14


class ButcherTableau:
    """The coefficients ``(A, b, c)`` of an ``s``-stage Runge–Kutta method.

    Checks its own consistency on construction: ``Σ b = 1`` (order ≥ 1) and
    ``Σ_j a_ij = c_i`` (stages see time consistently).

    Args:
        a: ``(s, s)`` stage matrix.
        b: ``(s,)`` weights.
        c: ``(s,)`` nodes (stage times as fractions of the step).
    """

    def __init__(self, a: Any, b: Any, c: Any) -> None:
        self.a = np.array(a, dtype=np.float64)
        self.b = np.array(b, dtype=np.float64)
        self.c = np.array(c, dtype=np.float64)
        s = self.b.size
        if self.a.shape != (s, s) or self.c.shape != (s,):
            raise ValueError(f"tableau shapes A {self.a.shape}, b {self.b.shape}, c {self.c.shape}")
        if abs(self.b.sum() - 1.0) > TABLEAU_TOLERANCE:
            raise ValueError(f"tableau weights must sum to 1 (sum {self.b.sum()!r})")
        if np.abs(self.a.sum(axis=1) - self.c).max() > TABLEAU_TOLERANCE:
            raise ValueError("tableau row sums of A must equal c")
        for arr in (self.a, self.b, self.c):
            arr.setflags(write=False)

    @property
    def stages(self) -> int:
        """Number of stages ``s``."""
        return self.b.size

    @property
    def explicit(self) -> bool:
        """True if ``A`` is strictly lower triangular."""
        return bool(np.all(np.triu(self.a) == 0.0))

    def stability_function(self, z: Any) -> np.ndarray:
        """``R(z) = 1 + z bᵀ (I − zA)⁻¹ 𝟙`` for complex ``z`` of any shape (``inf`` at a pole).

        For an explicit tableau ``A`` is nilpotent and ``R`` is the polynomial
        ``1 + Σ_k z^k bᵀ A^(k−1) 𝟙``, evaluated by Horner's rule (the linear solve would be
        ill-conditioned at large ``|z|``).
        """
        z = np.asarray(z, dtype=np.complex128)
        s = self.stages
        if self.explicit:
            coefficients = [1.0]
            power = np.ones(s)
            for _ in range(s):
                coefficients.append(float(self.b @ power))
                power = self.a @ power
            result = np.full(z.shape, coefficients[-1], dtype=np.complex128)
            for coefficient in reversed(coefficients[:-1]):
                result = result * z + coefficient
            return result
        # Implicit: R(z) = det(I − z(A − 𝟙bᵀ)) / det(I − zA), finite except at the poles.
        numerator = np.linalg.det(np.eye(s) - z[..., None, None] * (self.a - self.b[None, :]))
        denominator = np.linalg.det(np.eye(s) - z[..., None, None] * self.a)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.asarray(numerator / denominator, dtype=np.complex128)


class Stages:
    """The stage derivatives ``k_1 … k_s`` of one Runge–Kutta step.

    Each state part keeps its stages as the rows of one ``(s, size)`` array. A weighted sum
    ``Σ_j w_j k_j`` is one pass of :func:`~visviva.integrators.stage_sums.weighted_sum`, entry
    by entry in stage order, so every entry of every system is computed the same way whatever
    surrounds it (alone or in a batch).
    """

    def __init__(self, parts: tuple[np.ndarray, ...], count: int) -> None:
        self._rows = [np.empty((count, p.size), dtype=p.dtype) for p in parts]
        self._layout = [(rows, p.shape) for rows, p in zip(self._rows, parts, strict=True)]
        self.count = 0

    def append(self, rate: tuple[np.ndarray, ...]) -> None:
        """Store the next stage's derivative, one array per state part."""
        for rows, part in zip(self._rows, rate, strict=True):
            rows[self.count] = part.reshape(-1)
        self.count += 1

    def __getitem__(self, j: int) -> tuple[np.ndarray, ...]:
        """Stage ``j``'s derivative as state-shaped views."""
        return tuple([rows[j].reshape(shape) for rows, shape in self._layout])

    def _filled(self, weights: np.ndarray) -> int:
        """Number of stages ``weights`` spans, which must all be stored (rows start empty)."""
        n = len(weights)
        if n > self.count:
            raise IndexError(f"{n} weights but only {self.count} stages stored")
        return n

    def weighted(self, h: float, weights: np.ndarray) -> tuple[np.ndarray, ...]:
        """``h Σ_j weights[j] k_j`` over the first ``len(weights)`` stages, part by part."""
        from .stage_sums import weighted_sum

        self._filled(weights)
        scaled = h * np.asarray(weights, dtype=np.float64)
        sums = []
        for rows, shape in self._layout:
            total = np.empty(rows.shape[1], dtype=rows.dtype)
            weighted_sum(rows, scaled, total)
            sums.append(total.reshape(shape))
        return tuple(sums)

    def combine(
        self, base: tuple[np.ndarray, ...], h: float, weights: np.ndarray
    ) -> tuple[np.ndarray, ...]:
        """``base + h Σ_j weights[j] k_j``, part by part."""
        return tuple([b + d for b, d in zip(base, self.weighted(h, weights), strict=True)])


def initial_rate(system: System, state: State) -> tuple[np.ndarray, ...]:
    """``f`` at the state itself, reusing what the previous step left in the state."""
    if state.derivative is not None:
        return state.derivative
    return system.derivative(state.t, state.parts)


class ExplicitRungeKutta(Integrator):
    """An explicit Runge–Kutta method given by its Butcher tableau.

    Subclass it with a ``tableau`` and the usual declarations to add a method; see
    ``docs/integrators.md`` for a worked example registering Kutta's third-order method.
    """

    #: Stages combine derivatives, and ``q'`` is the system's (rigid bodies included).
    manifold_positions = True

    tableau: ClassVar[ButcherTableau]

    def step(self, system: System, state: State, dt: float) -> State:
        tableau = self.tableau
        y0 = state.parts
        stages = Stages(y0, tableau.stages)
        stages.append(initial_rate(system, state))
        for i in range(1, tableau.stages):
            stage = stages.combine(y0, dt, tableau.a[i, :i])
            stages.append(system.derivative(state.t + tableau.c[i] * dt, stage))
        return state.from_parts(state.t + dt, stages.combine(y0, dt, tableau.b))

    def stability_function(self, z: Any) -> np.ndarray:
        return self.tableau.stability_function(z)

    def compiled_step(self, problem: Problem) -> CompiledStep | None:
        from .compiled import runge_kutta_step

        return runge_kutta_step(self.tableau, problem)


class ExplicitEuler(ExplicitRungeKutta):
    """Explicit (forward) Euler: ``y' = y + h f(t, y)``.

    First order, one evaluation per step. Stable only inside the disc ``|1 + z| ≤ 1``, so it
    grows the energy of every undamped oscillation (seeds 000, 001, 004).
    """

    name = "explicit_euler"
    order = 1
    evaluations_per_step = 1
    cost = "1 f-evaluation"
    reference = "L. Euler, Institutionum calculi integralis, 1768; seeds 000-004"
    summary = "forward Euler: y + h f(t, y)"
    tableau = ButcherTableau([[0.0]], [1.0], [0.0])


class Midpoint(ExplicitRungeKutta):
    """Explicit midpoint (RK2): an Euler half step, then a full step with the midpoint slope.

    Second order, two evaluations per step (seed 002's "midpoint method").
    """

    name = "midpoint"
    order = 2
    evaluations_per_step = 2
    cost = "2 f-evaluations"
    reference = "C. Runge, Math. Ann. 46 (1895) 167-178; seed 002"
    summary = "explicit midpoint / RK2: slope at an Euler-predicted midpoint"
    tableau = ButcherTableau([[0.0, 0.0], [0.5, 0.0]], [0.0, 1.0], [0.0, 0.5])


class Heun(ExplicitRungeKutta):
    """Heun's method (explicit trapezoidal rule): average the slopes at both ends of an Euler step.

    Second order, two evaluations per step.
    """

    name = "heun"
    order = 2
    evaluations_per_step = 2
    cost = "2 f-evaluations"
    reference = "K. Heun, Z. Math. Phys. 45 (1900) 23-38"
    summary = "Heun / explicit trapezoidal: mean of the slopes at both ends of an Euler step"
    tableau = ButcherTableau([[0.0, 0.0], [1.0, 0.0]], [0.5, 0.5], [0.0, 1.0])


class RungeKutta4(ExplicitRungeKutta):
    """The classic fourth-order Runge–Kutta method (seed 002).

    Four evaluations per step; stable on the real axis down to ``z ≈ −2.785`` and on the
    imaginary axis for ``|z| ≤ 2√2``, so it damps undamped oscillations slightly.
    """

    name = "rk4"
    order = 4
    evaluations_per_step = 4
    cost = "4 f-evaluations"
    reference = "W. Kutta, Z. Math. Phys. 46 (1901) 435-453; seed 002"
    summary = "classic fourth-order Runge-Kutta"
    tableau = ButcherTableau(
        [[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1, 0]],
        [1 / 6, 1 / 3, 1 / 3, 1 / 6],
        [0, 0.5, 0.5, 1],
    )
