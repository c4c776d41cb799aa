"""Initial value problems: what to integrate, independent of how.

Two kinds, matching the two shapes mechanics comes in:

* :class:`FirstOrderProblem` — ``y'(t) = f(t, y)``, ``y(t0) = y0``.
* :class:`SecondOrderProblem` — ``M q''(t) = F(t, q, q')`` with the state kept split into
  positions ``q`` and velocities ``v = q'``, so that symplectic methods can treat them
  differently (seed 001: ``q' = v, v' = F/m``).

Both take a leading batch axis: ``y0`` of shape ``(batch, n)`` advances ``batch`` independent
systems together in one call. Every function is called once at construction, so a wrong shape or
a non-finite value is reported before any step is taken.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from .._validation import describe, real_number, state_array
from ..errors import ModelError
from .functions import UserFunction
from .mass import Mass
from .state import Layout, State
from .system import FirstOrderSystem, SecondOrderSystem

__all__ = ["FirstOrderProblem", "Problem", "SecondOrderProblem"]


class FirstOrderProblem:
    """The initial value problem ``y'(t) = f(t, y)``, ``y(t0) = y0``.

    Args:
        f: Right-hand side ``f(t, y) -> dy/dt`` (see :mod:`visviva.ode.functions` for NumPy vs
            Numba functions and the optional ``out`` argument).
        y0: Initial state, shape ``(n,)`` for one system or ``(batch, n)`` for a batch; real or
            complex.
        t0: Initial time [s].
        jacobian: Optional ``jacobian(t, y) -> ∂f/∂y`` of shape ``(n, n)`` (``(batch, n, n)``
            for a batch) or a ``scipy.sparse`` matrix. Implicit methods use finite differences
            of ``f`` when it is absent.
        energy: Optional ``energy(t, y)`` returning a quantity the exact flow conserves (one
            value per system); recorded every frame and used for drift figures.
        name: Short description used in messages and recordings.

    Example:
        >>> import numpy as np, visviva as vv
        >>> decay = vv.ode.FirstOrderProblem(lambda t, y: -2.0 * y, y0=[1.0])
        >>> sol = vv.solve(decay, method="rk4", dt=0.01, until=1.0)
        >>> bool(abs(sol.y[-1, 0] - np.exp(-2.0)) < 1e-9)
        True
    """

    kind: ClassVar[str] = "first_order"

    def __init__(
        self,
        f: Callable[..., Any],
        y0: Any,
        t0: float = 0.0,
        *,
        jacobian: Callable[..., Any] | None = None,
        energy: Callable[..., Any] | None = None,
        name: str = "first-order problem",
    ) -> None:
        self.y0 = state_array("y0", y0)
        self.t0 = real_number("t0", t0, unit=" s")
        self.f = UserFunction.inspect("f", f, forms={1: "f(t, y)"})
        self.jacobian = _optional("jacobian", jacobian, {1: "jacobian(t, y)"})
        self.energy = _optional("energy", energy, {1: "energy(t, y)"})
        self.name = str(name)
        _check_first_order(self)

    @property
    def batch_size(self) -> int | None:
        """Number of systems in the batch, or ``None`` for a single system."""
        return self.y0.shape[0] if self.y0.ndim == 2 else None

    @property
    def conservative(self) -> bool:
        """True if an energy is given: a quantity the exact flow conserves, so its change
        measures the integrator's error."""
        return self.energy is not None

    @property
    def size(self) -> int:
        """Number of state components ``n`` of one system."""
        return self.y0.shape[-1]

    def system(self) -> FirstOrderSystem:
        """A fresh run-time system (with zeroed work counters) for this problem."""
        return FirstOrderSystem.of(self)

    def initial_state(self) -> State:
        """The state the problem starts from (a copy of ``y0`` at ``t0``)."""
        return State(self.t0, (self.y0.copy(),), Layout.first_order())

    def __repr__(self) -> str:
        return f"FirstOrderProblem({self.name!r}, y0 shape {self.y0.shape}, t0={self.t0!r})"


class SecondOrderProblem:
    """The mechanical initial value problem ``M q'' = F(t, q, v)``, ``q(t0) = q0``, ``v(t0) = v0``.

    Construct it from the acceleration (unit mass) or, with :meth:`from_force`, from a force and
    a mass matrix. A function written ``acceleration(t, q)`` declares a force that does not
    depend on velocity: symplectic methods then keep their properties and methods that can
    reuse an evaluation from the previous step do so. Write ``acceleration(t, q, v)`` for
    damping, drag and other velocity-dependent forces.

    Args:
        acceleration: ``acceleration(t, q)`` or ``acceleration(t, q, v)`` returning ``q''``.
        q0: Initial coordinates, shape ``(n,)`` or ``(batch, n)``.
        v0: Initial velocities ``q'(t0)``, same shape as ``q0``.
        t0: Initial time [s].
        jacobian: Optional derivatives of the acceleration with the same arguments:
            ``jacobian(t, q) -> ∂a/∂q`` or ``jacobian(t, q, v) -> (∂a/∂q, ∂a/∂v)``; each
            ``(n, n)``, ``(batch, n, n)`` or sparse. Finite differences are used when absent.
        energy: Optional ``energy(t, q, v)``, one value per system (for a conservative system,
            the total energy); recorded every frame and used for drift figures.
        name: Short description used in messages and recordings.

    Example:
        >>> import numpy as np, visviva as vv
        >>> spring = vv.ode.SecondOrderProblem(lambda t, q: -q, q0=[1.0], v0=[0.0])
        >>> sol = vv.solve(spring, method="velocity_verlet", dt=0.01, until=np.pi)
        >>> bool(abs(sol.q[-1, 0] + 1.0) < 1e-4)
        True
    """

    kind: ClassVar[str] = "second_order"

    def __init__(
        self,
        acceleration: Callable[..., Any],
        q0: Any,
        v0: Any,
        t0: float = 0.0,
        *,
        jacobian: Callable[..., Any] | None = None,
        energy: Callable[..., Any] | None = None,
        name: str = "second-order problem",
    ) -> None:
        forms = {1: "acceleration(t, q)", 2: "acceleration(t, q, v)"}
        self._setup(
            UserFunction.inspect("acceleration", acceleration, forms=forms),
            None,
            q0,
            v0,
            t0,
            jacobian,
            energy,
            name,
        )

    @classmethod
    def from_force(
        cls,
        force: Callable[..., Any],
        mass: Any,
        q0: Any,
        v0: Any,
        t0: float = 0.0,
        *,
        jacobian: Callable[..., Any] | None = None,
        energy: Callable[..., Any] | None = None,
        name: str = "second-order problem",
    ) -> SecondOrderProblem:
        """Build the problem from a force ``F(t, q[, v])`` [N] and a constant mass matrix.

        Args:
            force: ``force(t, q)`` or ``force(t, q, v)`` returning ``F``, shape of ``q``.
            mass: Mass [kg]: a scalar, a diagonal broadcastable to ``q0``, dense matrices with
                one more axis than ``q0``, or a ``scipy.sparse`` matrix (see
                :class:`~visviva.ode.mass.Mass`).
            q0, v0, t0, energy, name: As for the constructor.
            jacobian: Optional ``jacobian(t, q) -> ∂F/∂q`` or
                ``jacobian(t, q, v) -> (∂F/∂q, ∂F/∂v)``.
        """
        problem = cls.__new__(cls)
        forms = {1: "force(t, q)", 2: "force(t, q, v)"}
        problem._setup(
            UserFunction.inspect("force", force, forms=forms),
            mass,
            q0,
            v0,
            t0,
            jacobian,
            energy,
            name,
        )
        return problem

    def _setup(
        self,
        force: UserFunction,
        mass: Any,
        q0: Any,
        v0: Any,
        t0: float,
        jacobian: Callable[..., Any] | None,
        energy: Callable[..., Any] | None,
        name: str,
    ) -> None:
        self.q0 = state_array("q0", q0)
        self.v0 = state_array("v0", v0)
        if self.v0.shape != self.q0.shape:
            raise ModelError(
                f"`v0` must have the shape of q0 {self.q0.shape} (got {self.v0.shape})"
            )
        self.t0 = real_number("t0", t0, unit=" s")
        self.force = force
        self.mass = None if mass is None else Mass(mass, self.q0)
        forms = (
            {2: "jacobian(t, q, v) -> (dF/dq, dF/dv)"}
            if force.state_arguments == 2
            else {1: "jacobian(t, q) -> dF/dq"}
        )
        self.jacobian = _optional("jacobian", jacobian, forms)
        self.energy = _optional("energy", energy, {2: "energy(t, q, v)"})
        self.name = str(name)
        _check_second_order(self)

    @property
    def batch_size(self) -> int | None:
        """Number of systems in the batch, or ``None`` for a single system."""
        return self.q0.shape[0] if self.q0.ndim == 2 else None

    @property
    def size(self) -> int:
        """Number of generalized coordinates ``n`` of one system."""
        return self.q0.shape[-1]

    @property
    def velocity_dependent(self) -> bool:
        """True if the force (acceleration) takes the velocities as an argument."""
        return self.force.state_arguments == 2

    @property
    def conservative(self) -> bool:
        """True if the recorded energy measures the integrator's error: an energy is given
        and the force does not read the velocities (no damping or drag to remove energy)."""
        return self.energy is not None and not self.velocity_dependent

    def system(self) -> SecondOrderSystem:
        """A fresh run-time system (with zeroed work counters) for this problem."""
        return SecondOrderSystem.of(self)

    def initial_state(self) -> State:
        """The state the problem starts from (copies of ``q0`` and ``v0`` at ``t0``)."""
        return State(self.t0, (self.q0.copy(), self.v0.copy()), Layout.positions_and_velocities())

    def __repr__(self) -> str:
        return f"SecondOrderProblem({self.name!r}, q0 shape {self.q0.shape}, t0={self.t0!r})"


Problem = FirstOrderProblem | SecondOrderProblem


def _optional(name: str, func: Any, forms: dict[int, str]) -> UserFunction | None:
    return None if func is None else UserFunction.inspect(name, func, forms=forms)


def _first_system(array: np.ndarray) -> np.ndarray:
    """A writable copy of system 0 of a batch (or of the single system)."""
    return np.array(array[0] if array.ndim == 2 else array)


def _call(function: UserFunction, t: float, *states: np.ndarray) -> Any:
    """Call a user function once on one system (or a NumPy one on the whole batch) for checks."""
    func = function.func
    try:
        if function.writes_out:
            out = np.full_like(states[0], np.nan)
            func(t, *states, out)
            return out
        return func(t, *states)
    except ModelError:
        raise
    except Exception as exc:
        raise ModelError(
            f"calling `{function.name}` at the initial state failed with "
            f"{type(exc).__name__}: {exc}"
        ) from exc


def _probe_states(function: UserFunction, *states: np.ndarray) -> tuple[np.ndarray, ...]:
    """The states to test a function with: system 0 for a Numba function, else everything."""
    if function.compiled:
        return tuple(_first_system(s) for s in states)
    return tuple(np.array(s) for s in states)


def _check_result(
    name: str, value: Any, shape: tuple[int, ...], what: str, complex_state: bool = True
) -> np.ndarray:
    if value is None:
        raise ModelError(
            f"`{name}` returned None; return {what}, or write it into a last argument named `out`"
        )
    import scipy.sparse as sp

    if sp.issparse(value):
        array = value
        if value.shape != shape:
            raise ModelError(f"`{name}` returned shape {value.shape}; expected {shape} ({what})")
        if not np.isfinite(value.data).all():
            raise ModelError(f"`{name}` returned non-finite values at the initial state")
        return array
    array = np.asarray(value)
    if array.shape != shape:
        raise ModelError(f"`{name}` returned shape {array.shape}; expected {shape} ({what})")
    if not np.issubdtype(array.dtype, np.number):
        raise ModelError(f"`{name}` returned dtype {array.dtype}; expected numbers ({what})")
    if np.iscomplexobj(array) and not complex_state:
        raise ModelError(
            f"`{name}` returned complex values for a real state; give the initial state as "
            "complex (for example y0 + 0j) to integrate in the complex plane"
        )
    bad = ~np.isfinite(array)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        where = index[0] if len(index) == 1 else index
        raise ModelError(
            f"`{name}` returned {describe(array[index])} at entry {where} for the initial state"
        )
    return array


def _check_first_order(problem: FirstOrderProblem) -> None:
    t0 = problem.t0
    (y,) = _probe_states(problem.f, problem.y0)
    f_y = _call(problem.f, t0, y)
    _check_result("f", f_y, y.shape, "dy/dt with the shape of y", np.iscomplexobj(y))
    if problem.jacobian is not None:
        (y,) = _probe_states(problem.jacobian, problem.y0)
        _check_result("jacobian", _call(problem.jacobian, t0, y), y.shape + y.shape[-1:], "df/dy")
    if problem.energy is not None:
        (y,) = _probe_states(problem.energy, problem.y0)
        expected = () if problem.energy.compiled or y.ndim == 1 else y.shape[:1]
        _check_result("energy", _call(problem.energy, t0, y), expected, "one value per system")


def _check_second_order(problem: SecondOrderProblem) -> None:
    t0, force = problem.t0, problem.force
    q, v = _probe_states(force, problem.q0, problem.v0)
    states = (q, v) if force.state_arguments == 2 else (q,)
    what = "the force" if problem.mass is not None else "the acceleration"
    _check_result(
        force.name,
        _call(force, t0, *states),
        q.shape,
        f"{what} with the shape of q",
        np.iscomplexobj(q),
    )
    jacobian = problem.jacobian
    if jacobian is not None:
        q, v = _probe_states(jacobian, problem.q0, problem.v0)
        matrix = q.shape + q.shape[-1:]
        if jacobian.state_arguments == 2:
            result = _call(jacobian, t0, q, v)
            if not (isinstance(result, tuple) and len(result) == 2):
                raise ModelError(
                    "`jacobian(t, q, v)` must return a pair (dF/dq, dF/dv) "
                    f"(got {type(result).__name__})"
                )
            _check_result("jacobian", result[0], matrix, "dF/dq")
            _check_result("jacobian", result[1], matrix, "dF/dv")
        else:
            _check_result("jacobian", _call(jacobian, t0, q), matrix, "dF/dq")
    if problem.energy is not None:
        q, v = _probe_states(problem.energy, problem.q0, problem.v0)
        expected = () if problem.energy.compiled or q.ndim == 1 else q.shape[:1]
        _check_result("energy", _call(problem.energy, t0, q, v), expected, "one value per system")
