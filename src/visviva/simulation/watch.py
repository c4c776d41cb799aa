"""The divergence watch: stop a blown-up run with an explanation instead of a screen of NaNs.

After every step the watch checks that every state component is finite and within the
divergence limit. When one is not, it raises :class:`~visviva.errors.SimulationDiverged`
naming the time, the step, the first offending component and its value, and asks the stability
advisor for the largest stable step of the method at the last finite state, so the message says
what to do next.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import SimulationDiverged

if TYPE_CHECKING:
    from ..integrators import Integrator
    from ..ode.state import State
    from ..ode.system import System

__all__ = [
    "DEFAULT_DIVERGENCE_LIMIT",
    "DivergenceWatch",
    "divergence_advice",
    "energy_drift_advice",
    "suggested_dt",
]

#: A state component beyond this many times the initial state's scale (at least 1) counts as
#: diverged: 1e10 for states of order one, scaled up for, say, orbits in metres.
DEFAULT_DIVERGENCE_LIMIT = 1e10


class DivergenceWatch:
    """Checks states for blow-up and explains it.

    Args:
        system: The system being integrated (for the advisor's Jacobian).
        method: The integrator in use.
        dt: The step in use [s] (for the message).
        initial: The initial state (its scale sets the default limit).
        limit: Largest allowed ``|component|``; ``None`` for
            ``DEFAULT_DIVERGENCE_LIMIT × max(1, max|initial state|)``.
    """

    def __init__(
        self,
        system: System,
        method: Integrator,
        dt: float,
        initial: State,
        limit: float | None = None,
    ) -> None:
        self.system = system
        self.method = method
        self.dt = dt
        self.limit = float(self.default_limit(initial) if limit is None else limit)

    @staticmethod
    def default_limit(initial: State) -> float:
        """``DEFAULT_DIVERGENCE_LIMIT × max(1, max|initial state|)``."""
        scale = max(float(np.max(np.abs(part))) for part in initial.parts)
        return DEFAULT_DIVERGENCE_LIMIT * max(1.0, scale)

    def healthy(self, state: State) -> bool:
        """True if every component is finite and within the limit."""
        # max() propagates NaN, so one pass per array catches NaN, inf and huge values.
        return all(bool(np.max(np.abs(part)) <= self.limit) for part in state.parts)

    def diverged(self, state: State, step: int, last_good: State) -> SimulationDiverged:
        """The exception describing why ``state`` (reached by the step of index ``step``, 0
        for the first) is not healthy; its message counts steps from 1, as people do."""
        component, value, system_index, entry = self._first_offender(state)
        suggestion = suggested_dt(self.system, self.method, last_good, system_index)
        problem = (
            "is not finite" if not np.isfinite(value) else (f"exceeds the limit {self.limit:.3g}")
        )
        message = (
            f"simulation diverged at t={state.t:.6g} s (step {step + 1}): {component} = {value!r} "
            f"{problem}. {divergence_advice(self.method, self.dt, suggestion)}"
        )
        return SimulationDiverged(
            message,
            t=state.t,
            step=step,
            component=component,
            value=value,
            suggested_dt=suggestion,
            system=system_index,
            entry=entry,
        )

    def _first_offender(self, state: State) -> tuple[str, float, int | None, tuple[int, int]]:
        """The first bad entry: its label (part name and index), value, batch system, and
        integrated array with its flat index there (in its row)."""
        for array, part in enumerate(state.parts):
            with np.errstate(invalid="ignore"):
                bad = ~(np.abs(part) <= self.limit)
            if bad.any():
                index = tuple(int(i) for i in np.argwhere(bad)[0])
                value = complex(part[index]) if np.iscomplexobj(part) else float(part[index])
                name, inside = state.layout.locate(array, index[-1])
                where = (*index[:-1], *inside)
                label = f"{name}[{', '.join(map(str, where))}]"
                if part.ndim == 2:
                    label += f" (system {index[0]})"
                system = index[0] if part.ndim == 2 else None
                return label, value, system, (array, index[-1])
        raise ValueError("state is healthy")


def suggested_dt(
    system: System, method: Integrator, state: State, system_index: int | None = None
) -> float | None:
    """The stability advisor's largest stable step [s] of ``method`` at ``state``.

    ``None`` if it could not be estimated, ``0`` if no step is stable, ``inf`` if every step
    is; ``system_index`` picks one system of a batch.
    """
    from ..analysis.advisor import largest_stable_step
    from ..analysis.stability import max_stable_dt, state_jacobian

    try:
        if system_index is None:
            return largest_stable_step(system, method, state)
        return max_stable_dt(method, jacobian=state_jacobian(system, state)[system_index])
    except Exception:
        return None


def divergence_advice(method: Integrator, dt: float, suggestion: float | None) -> str:
    """What to do about a blow-up, given the advisor's ``suggestion`` at the last finite state."""
    name = method.name
    if suggestion is None:
        return (
            f"The stability advisor could not estimate a stable step. Reduce dt (now "
            f"{dt:.3g} s) or try an implicit method such as 'backward_euler'."
        )
    if suggestion == 0.0:
        return _UNSTABLE_FOR_EVERY_STEP.format(name=name)
    if not np.isfinite(suggestion):
        return (
            f"{name!r} is stable for every step on this system's linearization at the last "
            "finite state, so the growth comes from the model itself (a growing mode or "
            "strong nonlinearity): check its parameters, or reduce dt."
        )
    verdict = "above" if dt > suggestion else "within"
    return (
        f"The stability advisor estimates the largest stable step of {name!r} at "
        f"dt ≈ {suggestion:.4g} s (from the Jacobian's eigenvalues at the last finite state); "
        f"dt = {dt:.4g} s is {verdict} it. Use dt below {0.9 * suggestion:.3g} s or an "
        "implicit method such as 'backward_euler'."
    )


def energy_drift_advice(method: Integrator, dt: float, suggestion: float | None) -> str:
    """What to do about a conservative system's energy changing too much, given the advisor's
    ``suggestion`` at the initial state."""
    name = method.name
    if suggestion == 0.0:
        return _UNSTABLE_FOR_EVERY_STEP.format(name=name)
    if suggestion is not None and np.isfinite(suggestion) and dt > suggestion:
        return (
            f"dt = {dt:.4g} s is above the largest stable step of {name!r}, which the "
            f"stability advisor estimates at {suggestion:.4g} s: use dt below "
            f"{0.9 * suggestion:.3g} s."
        )
    if method.symplectic:
        return (
            f"{name!r} keeps the energy error bounded but not small at dt = {dt:.4g} s: reduce "
            "dt (the error shrinks as dt^order)."
        )
    return (
        f"{name!r} is stable at dt = {dt:.4g} s but changes the energy steadily: reduce dt, or "
        "use a symplectic method ('velocity_verlet') whose energy error stays bounded over "
        "long runs."
    )


_UNSTABLE_FOR_EVERY_STEP = (
    "The linearized system has undamped oscillating modes, on which {name!r} is unstable for "
    "every step; use a symplectic method ('velocity_verlet', 'symplectic_euler') or an implicit "
    "one ('implicit_midpoint', 'backward_euler')."
)
