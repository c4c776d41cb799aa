"""The run-time face of a problem: what integrators call, with work counters.

A *system* evaluates a problem's functions on states (whole batches at once), supplies
Jacobians — the user's or finite differences of the same function — and counts the work. One
system is made per run, so the counters — and the run's :class:`~.workspace.Workspace`, where
the forces, stages and integrator keep their scratch — belong to that run; the problem itself
stays immutable and reusable.

Later models (particles, springs, rigid bodies) implement the same two interfaces, which is all
an integrator ever sees.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ..errors import ModelError
from .batching import batched
from .functions import UserFunction
from .state import Layout, State
from .workspace import Workspace

if TYPE_CHECKING:
    from .mass import Mass
    from .problems import FirstOrderProblem, SecondOrderProblem

__all__ = [
    "ContactConstraints",
    "FirstOrderSystem",
    "Kinematics",
    "SecondOrderSystem",
    "SpringNetwork",
    "Structure",
    "System",
    "WorkCounters",
]

#: Relative perturbation of forward finite differences: √ε balances truncation and round-off.
FINITE_DIFFERENCE_STEP = float(np.sqrt(np.finfo(np.float64).eps))


class Kinematics(Protocol):
    """How a second-order system's positions move where ``q' = v`` does not hold.

    A rigid body's configuration is a position and an orientation (a unit quaternion, 4
    numbers) and its "velocities" are its momenta ``P`` and ``L`` (3 + 3): ``q`` and ``v`` then
    differ in length (MuJoCo's ``nq`` and ``nv``), ``q' = K(q) v`` is a function of both, and
    an orientation must not be moved by "vector plus vector". Integrators that support such
    systems (``Integrator.manifold_positions``) go through these two methods, never ``q + h v``.
    """

    def rate(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``q'`` at ``(q, v)``, shape of ``q``."""
        ...

    def drift(self, q: np.ndarray, v: np.ndarray, h: float) -> np.ndarray:
        """The positions after ``h`` [s] of motion at the velocities (momenta) ``v`` held, as
        a new array: on the configuration manifold (unit quaternions stay unit)."""
        ...


class SpringNetwork(Protocol):
    """A system's springs as one network, for solvers made for springs
    (:mod:`visviva.integrators.fast_springs`): ``N`` points, ``S`` springs."""

    #: ``(N,)`` point masses [kg].
    mass: np.ndarray
    #: ``(N,)`` which points are held (in place, or on a handle's path).
    pinned: np.ndarray
    #: ``(S, 2)``, ``(S,)``, ``(S,)`` each spring's points (both ends, the first, the second).
    pairs: np.ndarray
    first: np.ndarray
    second: np.ndarray
    #: ``(S,)`` rest lengths [m] and stiffnesses [N/m].
    rest_length: np.ndarray
    stiffness: np.ndarray

    def elastic(self, t: float, x: np.ndarray) -> np.ndarray:
        """``(N, 3)`` the springs' elastic forces [N] at positions ``x`` (no dampers)."""
        ...

    def held_positions(self, t: float, x: np.ndarray) -> np.ndarray:
        """The positions ``x`` ``(N, 3)`` with the held points where they are held at ``t``."""
        ...


#: ``(q, reach) ↦ (particles, normals, push, friction)``: the particles against colliders at
#: positions ``q`` or within ``reach`` [m] of them, the colliders' outward normals, how far [m]
#: each must move along its normal to sit outside, and the friction coefficients.
ContactConstraints = Callable[[np.ndarray, float], tuple[np.ndarray, ...]]


class Structure:
    """What a system offers integrators beyond its equations. Each is ``None`` (or False)
    unless the system has it; an integrator that can use one reads it here, never probes."""

    #: How positions move where ``q' = v`` does not hold (rigid bodies' orientations).
    kinematics: Kinematics | None = None
    #: ``U(t, q)`` [J] if the force is ``−∇U(q) + D(q) v`` with ``D = ∂F/∂v`` symmetric:
    #: backward Euler's step is then the minimum of an incremental potential.
    potential: Callable[[float, np.ndarray], float] | None = None
    #: True if the Jacobians are block-sparse with 3×3 blocks (BSR) on a fixed pattern: what
    #: solvers for deformables (:mod:`visviva.integrators.projected_newton`) work on.
    block_jacobian: bool = False
    #: The colliders implicit steps may hold particles against.
    contact_constraints: ContactConstraints | None = None
    #: The springs as one network (a system of particles and springs only).
    spring_network: SpringNetwork | None = None


@dataclass
class WorkCounters:
    """Work done by one run. A call on a whole batch counts once.

    Attributes:
        f_evaluations: Evaluations of ``f`` (first-order) or of the force/acceleration
            (second-order), including those made for finite-difference Jacobians.
        jacobian_evaluations: Jacobians formed (analytic or by finite differences).
        linear_solves: Linear systems solved by implicit methods.
        newton_iterations: Newton iterations of implicit methods.
        krylov_iterations: Inner GMRES iterations of matrix-free (Newton–Krylov) linear solves;
            each costs one evaluation of ``f``, counted in ``f_evaluations`` too.
        line_search_steps: Newton steps shortened by the line search of implicit methods (each
            costs one evaluation of the force, counted in ``f_evaluations`` too).
        accepted_steps: Steps taken (for adaptive methods, the accepted ones).
        rejected_steps: Steps rejected by error control (adaptive methods only).
    """

    f_evaluations: int = 0
    jacobian_evaluations: int = 0
    linear_solves: int = 0
    newton_iterations: int = 0
    krylov_iterations: int = 0
    line_search_steps: int = 0
    accepted_steps: int = 0
    rejected_steps: int = 0

    def as_dict(self) -> dict[str, int]:
        """The counters as a plain dict (for JSON summaries)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


def evaluator(function: UserFunction, batch: bool, result: str = "array") -> Callable[..., Any]:
    """Return ``call(t, *states)`` evaluating a user function on a whole (batched) state.

    NumPy functions are called as they are (allocating ``out`` for those that write into it);
    a one-system Numba function on a batch is wrapped in a compiled parallel loop.
    """
    func = function.func
    if function.compiled and batch:
        return batched(function, result)
    if function.writes_out:

        def call_out(t: float, *states: np.ndarray) -> np.ndarray:
            out = np.empty_like(states[0])
            func(t, *states, out)
            return out

        return call_out
    return func


class FirstOrderSystem(Structure):
    """Evaluates ``y' = f(t, y)`` for integrators.

    Args:
        f: ``f(t, y) -> dy/dt`` on a whole (batched) state.
        jacobian: ``jacobian(t, y) -> ∂f/∂y`` (dense, batched dense or sparse), or ``None`` for
            finite differences of ``f``.
        energy: ``energy(t, y)``, one value per system, or ``None``.
        layout: The names of the state's parts (default: one part ``y``).
        counters: Work counters to add to (default: fresh ones).
        workspace: The run's storage (default: a fresh one).

    Attributes:
        counters: Work done so far in this run.
        workspace: The run's mutable storage (:class:`~.workspace.Workspace`), which the
            forces, stages and integrator stepping this system keep their scratch in.
        layout: The names of the state's parts.
    """

    second_order = False

    def __init__(
        self,
        f: Callable[..., Any],
        *,
        jacobian: Callable[..., Any] | None = None,
        energy: Callable[..., Any] | None = None,
        layout: Layout | None = None,
        counters: WorkCounters | None = None,
        workspace: Workspace | None = None,
    ) -> None:
        self._f = f
        self._jacobian = jacobian
        self._energy = energy
        self.layout = layout or Layout.first_order()
        self.counters = counters if counters is not None else WorkCounters()
        self.workspace = workspace if workspace is not None else Workspace()

    @classmethod
    def of(
        cls, problem: FirstOrderProblem, counters: WorkCounters | None = None
    ) -> FirstOrderSystem:
        """The system of a first-order problem."""
        batch = problem.y0.ndim == 2
        return cls(
            evaluator(problem.f, batch),
            jacobian=_optional_evaluator(problem.jacobian, batch, "matrix"),
            energy=_optional_evaluator(problem.energy, batch, "scalar"),
            counters=counters,
        )

    @property
    def has_energy(self) -> bool:
        """True if the problem defines a monitored energy."""
        return self._energy is not None

    @property
    def has_jacobian(self) -> bool:
        """True if the problem gives ``∂f/∂y`` (else it comes from finite differences)."""
        return self._jacobian is not None

    def jacobian_product(
        self, t: float, y: np.ndarray, direction: np.ndarray, rate: np.ndarray
    ) -> np.ndarray:
        """``∂f/∂y · u`` without forming the matrix: one forward difference of ``f`` along
        ``u`` (``rate`` = ``f(t, y)``). One system only (``y`` of shape ``(n,)``)."""
        return directional_difference(lambda s: self.rhs(t, y + s * direction), rate, y, direction)

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """``f(t, y)``, same shape as ``y``."""
        self.counters.f_evaluations += 1
        return _same_shape("f(t, y)", np.asarray(self._f(t, y)), y, t)

    def derivative(self, t: float, parts: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
        """Time derivative of the state arrays: ``(f(t, y),)``."""
        return (self.rhs(t, parts[0]),)

    def jacobian(self, t: float, y: np.ndarray, rate: np.ndarray | None = None) -> Any:
        """``∂f/∂y`` at ``(t, y)``: ``(n, n)``, ``(batch, n, n)`` or a sparse ``(n, n)``.

        Uses the problem's Jacobian when it has one, else forward finite differences of ``f``
        (``n`` extra evaluations; ``rate`` = ``f(t, y)`` saves one).
        """
        self.counters.jacobian_evaluations += 1
        if self._jacobian is not None:
            return self._jacobian(t, y)
        if rate is None:
            rate = self.rhs(t, y)
        return _finite_difference(lambda x: self.rhs(t, x), y, rate)

    def energy(self, state: State) -> np.ndarray | None:
        """The monitored energy of ``state``, one value per system, or ``None`` if the problem
        defines none."""
        if self._energy is None:
            return None
        return np.asarray(self._energy(state.t, state.parts[0]), dtype=np.float64)


class SecondOrderSystem(Structure):
    """Evaluates ``M q'' = F(t, q, v)`` for integrators.

    For a problem given by its acceleration, ``mass`` is ``None`` and ``force`` *is* the
    acceleration (unit mass), so implicit methods see one form. Scenes build one from the sum
    of their forces (:mod:`visviva.model`), with a layout naming the parts of ``q`` and ``v``.

    Args:
        force: ``force(t, q, v) -> F`` on a whole (batched) state, shape of ``q``.
        mass: The constant mass matrix, or ``None`` for unit mass.
        velocity_dependent: True if the force depends on ``v``; methods that would lose an
            order of accuracy with velocity-dependent forces use this to evaluate where they
            must.
        jacobian: ``jacobian(t, q, v) -> (∂F/∂q, ∂F/∂v or None)`` (dense, batched dense or
            sparse), or ``None`` for finite differences of the force.
        energy: ``energy(t, q, v)``, one value per system, or ``None``.
        layout: The names of the state's parts (default: ``q`` and ``v``).
        counters: Work counters to add to (default: fresh ones).
        workspace: The run's storage (default: a fresh one).
        kinematics: How the positions move with the velocities where that is not ``q' = v``
            (rigid bodies: orientations, momenta; see :class:`Kinematics`), or ``None``.

    Attributes:
        counters: Work done so far in this run.
        workspace: The run's mutable storage (:class:`~.workspace.Workspace`), which the
            forces, stages and integrator stepping this system keep their scratch in.
        mass: The mass matrix, or ``None``.
        velocity_dependent: True if the force takes ``v``.
        layout: The names of the state's parts.
        kinematics: The :class:`Kinematics`, or ``None`` for ``q' = v``.
    """

    second_order = True

    def __init__(
        self,
        force: Callable[..., Any],
        *,
        mass: Mass | None = None,
        velocity_dependent: bool = True,
        jacobian: Callable[..., Any] | None = None,
        energy: Callable[..., Any] | None = None,
        layout: Layout | None = None,
        counters: WorkCounters | None = None,
        workspace: Workspace | None = None,
        kinematics: Kinematics | None = None,
    ) -> None:
        self._force = force
        self.kinematics = kinematics
        self.mass = mass
        self.velocity_dependent = velocity_dependent
        self._jacobian = jacobian
        self._energy = energy
        self.layout = layout or Layout.positions_and_velocities()
        self.counters = counters if counters is not None else WorkCounters()
        self.workspace = workspace if workspace is not None else Workspace()

    @classmethod
    def of(
        cls, problem: SecondOrderProblem, counters: WorkCounters | None = None
    ) -> SecondOrderSystem:
        """The system of a second-order problem."""
        batch = problem.q0.ndim == 2
        moving = problem.force.state_arguments == 2
        force = evaluator(problem.force, batch)
        jacobian = None
        if problem.jacobian is not None:
            kind = "pair" if problem.jacobian.state_arguments == 2 else "matrix"
            jacobian = evaluator(problem.jacobian, batch, kind)
        energy = _optional_evaluator(problem.energy, batch, "scalar")
        if moving:
            return cls(
                force,
                mass=problem.mass,
                velocity_dependent=True,
                jacobian=jacobian,
                energy=energy,
                counters=counters,
            )
        still = jacobian
        return cls(
            lambda t, q, v: force(t, q),
            mass=problem.mass,
            velocity_dependent=False,
            # The problem checked that the Jacobian takes the same arguments as the force.
            jacobian=None if still is None else (lambda t, q, v: (still(t, q), None)),
            energy=energy,
            counters=counters,
        )

    @property
    def has_energy(self) -> bool:
        """True if the problem defines a monitored energy."""
        return self._energy is not None

    @property
    def has_jacobian(self) -> bool:
        """True if the problem gives ``∂F/∂q`` (and ``∂F/∂v``); else finite differences."""
        return self._jacobian is not None

    def force_product(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        dq: np.ndarray,
        dv: np.ndarray | None,
        force: np.ndarray,
    ) -> np.ndarray:
        """``∂F/∂q · dq + ∂F/∂v · dv`` without forming a matrix: one forward difference of the
        force along ``(dq, dv)`` (``force`` = ``F(t, q, v)``; ``dv = None`` for zero). One
        system only (``q`` of shape ``(n,)``)."""
        if dv is None or not self.velocity_dependent:
            return directional_difference(lambda s: self.force(t, q + s * dq, v), force, q, dq)
        state, direction = np.concatenate([q, v]), np.concatenate([dq, dv])
        return directional_difference(
            lambda s: self.force(t, q + s * dq, v + s * dv), force, state, direction
        )

    def force(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``F(t, q, v)`` (the acceleration for a problem without mass), shape of ``v``."""
        self.counters.f_evaluations += 1
        what = "the force F(t, q, v)" if self.velocity_dependent else "the force F(t, q)"
        return _same_shape(what, np.asarray(self._force(t, q, v)), v, t)

    def acceleration(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``v' = M⁻¹ F(t, q, v)``, shape of ``v``."""
        force = self.force(t, q, v)
        return force if self.mass is None else self.mass.solve(force)

    def position_rate(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``q'``: ``v`` itself, or what the :class:`Kinematics` make of it."""
        return v if self.kinematics is None else self.kinematics.rate(q, v)

    def drift(self, q: np.ndarray, v: np.ndarray, h: float) -> np.ndarray:
        """The positions after ``h`` [s] at the velocities ``v`` held: ``q + h v``, or the
        :class:`Kinematics`' update (a rotation for an orientation)."""
        return q + h * v if self.kinematics is None else self.kinematics.drift(q, v, h)

    def derivative(self, t: float, parts: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
        """Time derivative of ``(q, v)``: ``(q', v')``, ``q' = v`` unless the system has
        :class:`Kinematics`."""
        q, v = parts
        return (self.position_rate(q, v), self.acceleration(t, q, v))

    def force_jacobian(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        force: np.ndarray | None = None,
        *,
        form: str = "exact",
    ) -> tuple[Any, Any]:
        """``(∂F/∂q, ∂F/∂v)`` at ``(t, q, v)``; the second is ``None`` for position-only forces.

        Each is ``(n, n)``, ``(batch, n, n)`` or sparse ``(n, n)``. Uses the problem's Jacobian
        when given, else forward finite differences of ``F`` (``force`` = ``F(t, q, v)`` saves
        one evaluation). ``form`` ``"symmetric"`` asks for ``∂F/∂q`` without the
        non-symmetric part of velocity-dependent forces (``−∇²U`` where ``F = −∇U + D v``),
        ``"definite"`` for the same with each element's negative stiffness dropped, where the
        system knows them (a scene's springs); a plain problem gives its exact Jacobian.
        """
        self.counters.jacobian_evaluations += 1
        if self._jacobian is not None:
            stiffness, damping = self._jacobian(t, q, v)
            return stiffness, damping
        if force is None:
            force = self.force(t, q, v)
        stiffness = _finite_difference(lambda x: self.force(t, x, v), q, force)
        if not self.velocity_dependent:
            return stiffness, None
        damping = _finite_difference(lambda x: self.force(t, q, x), v, force)
        return stiffness, damping

    def energy(self, state: State) -> np.ndarray | None:
        """The monitored energy of ``state``, one value per system, or ``None`` if the problem
        defines none."""
        if self._energy is None:
            return None
        q, v = state.parts
        return np.asarray(self._energy(state.t, q, v), dtype=np.float64)


System = FirstOrderSystem | SecondOrderSystem


def _optional_evaluator(
    function: UserFunction | None, batch: bool, result: str
) -> Callable[..., Any] | None:
    return None if function is None else evaluator(function, batch, result)


def _same_shape(what: str, value: np.ndarray, state: np.ndarray, t: float) -> np.ndarray:
    """``value`` if it has the state's shape; else the user's function is wrong: say so."""
    if value.shape != state.shape:
        raise ModelError(
            f"{what} returned shape {value.shape} at t = {float(t)!r}; it must return the state's "
            f"shape {state.shape} at every call"
        )
    return value


def directional_difference(
    along: Callable[[float], np.ndarray],
    value: np.ndarray,
    x: np.ndarray,
    direction: np.ndarray,
) -> np.ndarray:
    """``(g(x + εu) − g(x)) / ε``: the derivative of ``g`` along ``u`` from one evaluation.

    ``along(s)`` evaluates ``g(x + s·u)``; ``value`` is ``g(x)``. The step
    ``ε = √ε_mach (1 + ‖x‖) / ‖u‖`` balances truncation and round-off for any scale of ``u``
    (Knoll & Keyes, "Jacobian-free Newton–Krylov methods", J. Comput. Phys. 193, 2004, §2.2).
    """
    norm = float(np.linalg.norm(direction))
    if norm == 0.0:
        return np.zeros_like(value)
    step = FINITE_DIFFERENCE_STEP * (1.0 + float(np.linalg.norm(x))) / norm
    return (along(step) - value) / step


def _finite_difference(
    func: Callable[[np.ndarray], np.ndarray], x: np.ndarray, fx: np.ndarray
) -> np.ndarray:
    """Forward-difference Jacobian ``∂func/∂x``: ``(n, n)`` or ``(batch, n, n)``.

    Column ``j`` perturbs coordinate ``j`` of every system at once, so a batch costs ``n``
    evaluations, not ``batch × n``.
    """
    n = x.shape[-1]
    jacobian = np.empty(x.shape + (n,), dtype=np.result_type(x, fx))
    for j in range(n):
        step = FINITE_DIFFERENCE_STEP * np.maximum(1.0, np.abs(x[..., j]))
        shifted = x.copy()
        shifted[..., j] += step
        # Divide by the step actually taken, which rounding makes differ from `step`.
        taken = (shifted[..., j] - x[..., j]).real
        jacobian[..., :, j] = (func(shifted) - fx) / taken[..., None]
    return jacobian
