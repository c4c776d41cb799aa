"""Newton's method for the one implicit stage of backward Euler, trapezoidal and implicit midpoint.

All three methods solve one equation of the same shape (seed 004, "Implicit Euler"):

* first-order problems: ``Y = y_b + θh f(t*, Y)`` for the unknown ``Y``, with Newton matrix
  ``I − θh ∂f/∂y``;
* second-order problems: ``Q = q_b + θh V`` and ``M (V − v_b) = θh F(t*, Q, V)``. Eliminating
  ``Q`` leaves the velocity ``V`` as the only unknown and the ``n × n`` Newton matrix
  ``M − θh ∂F/∂v − (θh)² ∂F/∂q`` — the form of Baraff & Witkin's implicit cloth, symmetric
  for conservative forces, half the size of the first-order ``2n × 2n`` system.

Each iteration evaluates the residual and the Jacobian (the user's, or finite differences of the
same function) and solves one linear system: batched dense LAPACK for ``(batch, n, n)`` matrices,
SuperLU for ``scipy.sparse`` ones. A problem without an analytic Jacobian and with more than
:data:`KRYLOV_THRESHOLD` unknowns is solved matrix-free instead (Jacobian-free Newton–Krylov):
GMRES on products of the Newton matrix with vectors, each one forward difference of ``f``
along the vector, preconditioned by the mass matrix's diagonal, so memory stays ``O(n)``.
For one second-order system, a step that makes the residual's norm grow is halved until it
shrinks (Armijo backtracking, which costs nothing when full steps work).
Iteration stops when every component's update is below ``atol + rtol·|value|``; if that does
not happen within ``max_iterations`` the step raises
:class:`~visviva.errors.NewtonConvergenceError` — never a silently wrong answer.

References:
    D. Baraff, A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998, §4.
    D. A. Knoll, D. E. Keyes, "Jacobian-free Newton–Krylov methods: a survey of approaches
    and applications", J. Comput. Phys. 193 (2004) 357–397.
    Y. Saad, M. H. Schultz, "GMRES: a generalized minimal residual algorithm for solving
    nonsymmetric linear systems", SIAM J. Sci. Stat. Comput. 7 (1986) 856–869.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import _stop
from .._validation import real_number, whole_number
from ..errors import Interrupted, NewtonConvergenceError

if TYPE_CHECKING:
    from ..ode.mass import Mass
    from ..ode.system import FirstOrderSystem, SecondOrderSystem, System

__all__ = [
    "KRYLOV_THRESHOLD",
    "NewtonOptions",
    "identity_minus",
    "linear_solve",
    "mass_minus",
    "solve_stage",
]

#: Unknowns above which a problem without an analytic Jacobian is solved matrix-free: a
#: finite-difference Jacobian costs n evaluations of f and n² memory per Newton iteration
#: (6003 unknowns: 6003 force evaluations and 288 MB), GMRES a few products.
KRYLOV_THRESHOLD = 1000
#: Relative residual GMRES reaches in each Newton iteration: small enough that the Newton
#: update, and so the stopping rule, is the one a direct solve would give.
KRYLOV_RTOL = 1e-9
#: Armijo's fraction: a step must shrink the residual's norm by at least this share of the step.
ARMIJO = 1e-4
#: Halvings a backtracking line search may take (the last step is 1/64 of Newton's).
LINE_SEARCH_HALVINGS = 6
#: GMRES restart length and restarts allowed per linear solve.
KRYLOV_RESTART = 40
KRYLOV_MAX_RESTARTS = 10


@dataclass(frozen=True)
class NewtonOptions:
    """Stopping rule of Newton's method.

    Attributes:
        rtol: Relative tolerance on each component of the Newton update.
        atol: Absolute tolerance on each component of the Newton update (state units).
        max_iterations: Iterations allowed before the step fails.
    """

    rtol: float = 1e-10
    atol: float = 1e-12
    max_iterations: int = 20

    def __post_init__(self) -> None:
        real_number("rtol", self.rtol, nonnegative=True)
        real_number("atol", self.atol, nonnegative=True)
        whole_number("max_iterations", self.max_iterations, minimum=1)
        if self.rtol == 0.0 and self.atol == 0.0:
            real_number("atol", self.atol, positive=True)


def stop_if_asked(t: float) -> None:
    """Between Newton iterations: raise :class:`~visviva.errors.Interrupted` if the job was
    asked to stop (Ctrl-C), so that a long solve answers within an iteration; the simulation
    loop drops the half-done step and keeps the last whole one."""
    name = _stop.requested()
    if name is not None:
        raise Interrupted(name, t)


def solve_stage(
    system: System,
    t_star: float,
    base: tuple[np.ndarray, ...],
    theta_h: float,
    options: NewtonOptions,
) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
    """Solve the implicit stage equation described in the module docstring.

    Args:
        system: The system being integrated.
        t_star: Time at which the implicit evaluation happens [s].
        base: ``(y_b,)`` or ``(q_b, v_b)``: the explicit part of the stage.
        theta_h: ``θh`` [s], the weight of the implicit evaluation.
        options: Tolerances and iteration cap.

    Returns:
        The stage ``(Y,)`` or ``(Q, V)``, and the derivative there, ``f(t*, Y)`` or
        ``q''(t*, Q, V)``, recovered from the stage equation without another evaluation.
    """
    if not system.second_order:
        return _solve_first_order(system, t_star, base[0], theta_h, options)  # type: ignore[arg-type]
    return _solve_second_order(system, t_star, base, theta_h, options)  # type: ignore[arg-type]


def _solve_first_order(
    system: FirstOrderSystem, t: float, y_base: np.ndarray, theta_h: float, options: NewtonOptions
) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
    y = y_base.copy()
    matrix_free = _matrix_free(system, y)
    iteration, norm = 0, np.inf
    while iteration < options.max_iterations:
        stop_if_asked(t)
        iteration += 1
        rate = system.rhs(t, y)
        residual = y - y_base - theta_h * rate
        if matrix_free:
            product = _identity_minus_product(system, t, y.copy(), rate, theta_h)
            update = _krylov_solve(system, product, -residual, None)
        else:
            jacobian = system.jacobian(t, y, rate)
            update = linear_solve(system, identity_minus(jacobian, theta_h, y.shape), -residual)
        y += update
        system.counters.newton_iterations += 1
        norm = _update_norm(update, y, options)
        if norm <= 1.0:
            return (y,), (y - y_base) / theta_h
        if not np.isfinite(norm):
            break
    raise _failure(t, iteration, norm)


def _solve_second_order(
    system: SecondOrderSystem,
    t: float,
    base: tuple[np.ndarray, ...],
    theta_h: float,
    options: NewtonOptions,
) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
    q_base, v_base = base
    mass = system.mass
    v = v_base.copy()
    matrix_free = _matrix_free(system, v)
    # The last step, to back along if it made the residual grow: (V before it, the update,
    # the residual's norm before it).
    last: tuple[np.ndarray, np.ndarray, float] | None = None
    iteration, norm = 0, np.inf
    while iteration < options.max_iterations:
        stop_if_asked(t)
        iteration += 1
        q, force, residual = _stage_residual(system, t, q_base, v_base, v, theta_h)
        if last is not None and v.ndim == 1:
            full = (q, force, residual)
            v, q, force, residual = _backtrack(system, t, q_base, v_base, theta_h, full, last)
        if matrix_free:
            product = _mass_minus_product(system, t, q, v.copy(), force, theta_h)
            update = _krylov_solve(system, product, -residual, mass)
        else:
            stiffness, damping = system.force_jacobian(t, q, v, force)
            matrix = mass_minus(mass, damping, stiffness, theta_h, v.shape)
            update = linear_solve(system, matrix, -residual)
        last = (v.copy(), update, float(np.linalg.norm(residual)))
        v = v + update
        system.counters.newton_iterations += 1
        norm = _update_norm(update, v, options)
        if norm <= 1.0:
            return (q_base + theta_h * v, v), (v - v_base) / theta_h
        if not np.isfinite(norm):
            break
    raise _failure(t, iteration, norm)


def _stage_residual(
    system: SecondOrderSystem,
    t: float,
    q_base: np.ndarray,
    v_base: np.ndarray,
    v: np.ndarray,
    theta_h: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``Q``, ``F(t, Q, V)`` and the residual ``M (V − v_b) − θh F`` at the velocity ``V``."""
    q = q_base + theta_h * v
    force = system.force(t, q, v)
    momentum_change = v - v_base if system.mass is None else system.mass.apply(v - v_base)
    return q, force, momentum_change - theta_h * force


def _backtrack(
    system: SecondOrderSystem,
    t: float,
    q_base: np.ndarray,
    v_base: np.ndarray,
    theta_h: float,
    full: tuple[np.ndarray, np.ndarray, np.ndarray],
    last: tuple[np.ndarray, np.ndarray, float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The iterate after the last Newton step (``full``: its ``Q``, force and residual),
    shortened — halved up to :data:`LINE_SEARCH_HALVINGS` times — until the residual's norm
    has decreased by Armijo's fraction. A full step that decreases it, the rule near a
    solution, costs nothing extra.

    Far from a solution a full step can overshoot: a cloth buckling against a collider makes
    its springs' stiffness indefinite and Newton's linear model wrong. The residual is the
    merit function rather than an energy because damping and fields without a potential have
    none.
    """
    v_before, update, norm_before = last
    q, force, residual = full
    v = v_before + update
    step = 1.0
    for _ in range(LINE_SEARCH_HALVINGS):
        if np.linalg.norm(residual) <= (1.0 - ARMIJO * step) * norm_before:
            break
        step *= 0.5
        system.counters.line_search_steps += 1
        v = v_before + step * update
        q, force, residual = _stage_residual(system, t, q_base, v_base, v, theta_h)
    return v, q, force, residual


def _matrix_free(system: System, state: np.ndarray) -> bool:
    """Newton–Krylov for one large system without an analytic Jacobian."""
    return state.ndim == 1 and state.size > KRYLOV_THRESHOLD and not system.has_jacobian


def _identity_minus_product(
    system: FirstOrderSystem, t: float, y: np.ndarray, rate: np.ndarray, theta_h: float
) -> Callable[[np.ndarray], np.ndarray]:
    """``u ↦ (I − θh ∂f/∂y) u`` at ``y`` (``rate`` = ``f(t, y)``), one f-evaluation each."""
    return lambda u: u - theta_h * system.jacobian_product(t, y, u, rate)


def _mass_minus_product(
    system: SecondOrderSystem,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    force: np.ndarray,
    theta_h: float,
) -> Callable[[np.ndarray], np.ndarray]:
    """``u ↦ (M − θh ∂F/∂v − (θh)² ∂F/∂q) u`` at ``(q, v)`` (``force`` = ``F(t, q, v)``): when
    the unknown ``V`` moves by ``u``, ``Q = q_b + θh V`` moves by ``θh u``."""
    mass = system.mass

    def product(u: np.ndarray) -> np.ndarray:
        change = system.force_product(t, q, v, theta_h * u, u, force)
        return (u if mass is None else mass.apply(u)) - theta_h * change

    return product


def _krylov_solve(
    system: System, product: Callable[[np.ndarray], np.ndarray], rhs: np.ndarray, mass: Mass | None
) -> np.ndarray:
    """Solve ``A x = rhs`` by restarted GMRES given ``x ↦ A x``, preconditioned by the inverse
    of the mass matrix's diagonal (the Newton matrix is ``M`` plus ``O(h)`` terms)."""
    from scipy.sparse.linalg import LinearOperator, gmres

    n = rhs.size
    system.counters.linear_solves += 1
    operator = LinearOperator((n, n), matvec=lambda u: product(u.ravel()), dtype=rhs.dtype)
    preconditioner = None
    if mass is not None:
        inverse = 1.0 / np.broadcast_to(mass.diagonal(), rhs.shape)
        preconditioner = LinearOperator((n, n), matvec=lambda u: inverse * u.ravel())

    def count(_: Any) -> None:
        system.counters.krylov_iterations += 1

    solution, _ = gmres(
        operator,
        rhs,
        rtol=KRYLOV_RTOL,
        atol=0.0,
        restart=KRYLOV_RESTART,
        maxiter=KRYLOV_MAX_RESTARTS,
        M=preconditioner,
        callback=count,
        callback_type="pr_norm",
    )
    # Not converged within the restarts: the update is still GMRES's best; Newton's stopping
    # rule decides whether the step converged.
    return np.asarray(solution)


def _update_norm(update: np.ndarray, value: np.ndarray, options: NewtonOptions) -> float:
    """Largest ``|Δ_i| / (atol + rtol |x_i|)`` over every component of every system."""
    scale = options.atol + options.rtol * np.abs(value)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.abs(update) / scale
    largest = ratio.max()
    return float(largest) if np.isfinite(largest) else float("inf")


def _failure(t: float, iterations: int, norm: float) -> NewtonConvergenceError:
    reason = (
        "the iterates became non-finite"
        if not np.isfinite(norm)
        else f"the last update was {norm:.3g} times the tolerance"
    )
    return NewtonConvergenceError(
        f"Newton's method did not converge in the implicit step at t={t!r} after {iterations} "
        f"iterations ({reason}). Reduce dt, check the Jacobian against finite differences "
        "(or omit it to use them), or raise max_iterations.",
        t=t,
        step=None,
        iterations=iterations,
        update_norm=norm,
    )


def identity_minus(jacobian: Any, theta_h: float, shape: tuple[int, ...]) -> Any:
    """``I − θh J`` in the storage of ``J`` (dense, batched dense or sparse)."""
    import scipy.sparse as sp

    if sp.issparse(jacobian):
        return (sp.identity(shape[-1], format="csc") - theta_h * jacobian).tocsc()
    return np.eye(shape[-1]) - theta_h * np.asarray(jacobian)


def mass_minus(
    mass: Mass | None, damping: Any, stiffness: Any, theta_h: float, shape: tuple[int, ...]
) -> Any:
    """``M − θh ∂F/∂v − (θh)² ∂F/∂q``, sparse if any term is sparse and M allows it."""
    import scipy.sparse as sp

    n = shape[-1]
    terms = [t for t in (damping, stiffness) if t is not None]
    sparse = any(sp.issparse(t) for t in terms) or (mass is not None and mass.kind == "sparse")
    if sparse and len(shape) == 1 and (mass is None or mass.kind != "dense"):
        if mass is None:
            matrix = sp.identity(n, format="csc")
        elif mass.kind == "sparse":
            matrix = mass.values
        else:
            matrix = sp.diags(np.broadcast_to(mass.values, shape), format="csc")
        if damping is not None:
            matrix = matrix - theta_h * sp.csc_matrix(damping)
        return (matrix - theta_h**2 * sp.csc_matrix(stiffness)).tocsc()
    dense = np.broadcast_to(np.eye(n), shape + (n,)) if mass is None else mass.dense(shape)
    matrix = dense - theta_h**2 * _dense(stiffness)
    if damping is not None:
        matrix = matrix - theta_h * _dense(damping)
    return matrix


def _dense(matrix: Any) -> np.ndarray:
    import scipy.sparse as sp

    return matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix)


def linear_solve(system: System, matrix: Any, rhs: np.ndarray) -> np.ndarray:
    """Solve ``matrix · x = rhs`` (batched dense or sparse) and count it."""
    import scipy.sparse as sp

    system.counters.linear_solves += 1
    if sp.issparse(matrix):
        from scipy.sparse.linalg import spsolve

        return np.asarray(spsolve(matrix, rhs)).reshape(rhs.shape)
    try:
        return np.linalg.solve(matrix, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:
        # A singular Newton matrix: report as a non-finite update, so the step fails cleanly.
        return np.full_like(rhs, np.nan)
