"""What every time integrator declares and does.

A method is a small class: its properties are class attributes (order, implicit, symplectic,
cost, reference) and :meth:`Integrator.step` maps a state to the next without keeping anything
between calls. Its stability function ``R(z)`` — the factor one step multiplies the solution of
the test equation ``y' = λy`` by, with ``z = hλ`` — comes for free: by default it is *measured*
by applying the method's own ``step`` to the test equation (see :mod:`.linear_test`), so a
user-registered method gets stability regions, stability intervals and the step-size advisor
without writing ``R(z)`` down.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..errors import ModelError

if TYPE_CHECKING:
    from ..ode.problems import Problem
    from ..ode.state import State
    from ..ode.system import System

__all__ = ["CompiledStep", "Integrator"]


class CompiledStep:
    """A Numba one-system step kernel that the compiled run loop calls.

    Attributes:
        kernel: ``kernel(t, h, y, work, fresh) -> evaluations``: advances the stacked
            one-system state ``y`` (``y`` for first-order, ``[q, v]`` for second-order
            problems, length ``m``) in place by ``h``; ``work`` is the system's scratch of shape
            ``(rows, m)``, kept across steps; ``fresh`` is true when ``work`` holds nothing
            from a previous step.
        rows: Rows of the scratch array.
    """

    def __init__(self, kernel: Callable[..., int], rows: int) -> None:
        self.kernel = kernel
        self.rows = rows


class Integrator(ABC):
    """Base class of the time integrators.

    Class attributes (declared by every method):
        name: Registry name, ``snake_case``.
        order: Order of global accuracy ``p``: the error at a fixed time scales as ``dt**p``.
        implicit: True if a step solves a (non)linear system (Newton's method).
        symplectic: True if the map ``(q, v) -> (q', v')`` is symplectic for position-only
            forces: energy then oscillates near its initial value without drift.
        adaptive: True if the method can choose its own step from an error estimate.
        second_order_only: True if the method needs the split ``(q, v)`` state of a
            :class:`~visviva.ode.SecondOrderProblem`.
        manifold_positions: True if the method steps systems whose positions do not move as
            ``q' = v`` (rigid bodies' orientations; :class:`~visviva.ode.system.Kinematics`),
            through ``system.position_rate`` and ``system.drift``.
        evaluations_per_step: Evaluations of ``f`` per step of an explicit method (with
            position-only forces, after the first step); per Newton iteration for an implicit one.
        cost: One line on the work per step, for tables.
        reference: Where the method comes from.
        summary: One line saying what the method is.
    """

    name: ClassVar[str]
    order: ClassVar[int]
    implicit: ClassVar[bool] = False
    symplectic: ClassVar[bool] = False
    adaptive: ClassVar[bool] = False
    second_order_only: ClassVar[bool] = False
    manifold_positions: ClassVar[bool] = False
    evaluations_per_step: ClassVar[int]
    cost: ClassVar[str]
    reference: ClassVar[str]
    summary: ClassVar[str]

    @abstractmethod
    def step(self, system: System, state: State, dt: float) -> State:
        """Advance ``state`` by ``dt`` seconds and return the new state.

        Args:
            system: Evaluates the problem (:class:`~visviva.ode.system.FirstOrderSystem` or
                :class:`~visviva.ode.system.SecondOrderSystem`).
            state: The current state; never modified.
            dt: Step [s]. May be negative (integrating backwards in time).
        """

    def check(self, system: System) -> None:
        """Raise :class:`~visviva.errors.ModelError` if this method cannot integrate ``system``."""
        if self.second_order_only and not system.second_order:
            raise ModelError(
                f"method {self.name!r} needs the split (q, v) state of a second-order problem; "
                "build it with vv.ode.SecondOrderProblem, or pick a method that integrates "
                "first-order problems (e.g. 'rk4')"
            )
        if system.kinematics is not None and not self.manifold_positions:
            raise ModelError(
                f"method {self.name!r} cannot step rigid bodies (their orientations do not move "
                "as q' = v); pick one that does: 'symplectic_euler' (the default), "
                "'velocity_verlet', 'leapfrog', 'symplectic_euler_position_first', "
                "'explicit_euler', 'midpoint', 'heun', 'rk4' or 'dopri5'"
            )

    def stability_function(self, z: Any) -> np.ndarray:
        """``R(z)``: one step's amplification of the test equation ``y' = λy`` at ``z = hλ``.

        The method is stable for ``z`` where ``|R(z)| ≤ 1``. For methods on the split ``(q, v)``
        state, ``R(z)`` is the dominant eigenvalue of one step on the oscillator whose
        characteristic roots are ``λ`` and its conjugate (see :mod:`.linear_test`).

        Args:
            z: Complex number(s) ``hλ``, any shape.

        Returns:
            Complex array with the shape of ``z``.
        """
        from .linear_test import measured_stability_function

        return measured_stability_function(self, z)

    def compiled_step(self, problem: Problem) -> CompiledStep | None:
        """A Numba step kernel for ``problem``, or ``None`` if this method has none."""
        return None

    def describe(self) -> dict[str, Any]:
        """The declared properties as a plain dict (for tables and JSON)."""
        return {
            "name": self.name,
            "order": self.order,
            "implicit": self.implicit,
            "symplectic": self.symplectic,
            "adaptive": self.adaptive,
            "second_order_only": self.second_order_only,
            "cost": self.cost,
            "summary": self.summary,
            "reference": self.reference,
        }

    def __repr__(self) -> str:
        return f"<integrator {self.name!r}: order {self.order}>"
