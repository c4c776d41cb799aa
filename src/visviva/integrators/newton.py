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
SuperLU for ``scipy.sparse`` ones. Iteration stops when every component's update is below
``atol + rtol·|value|``; if that does not happen within ``max_iterations`` the step raises
:class:`~visviva.errors.NewtonConvergenceError` — never a silently wrong answer.

Reference:
    D. Baraff, A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998, §4.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import real_number, whole_number
from ..errors import NewtonConvergenceError

if TYPE_CHECKING:
    from ..ode.mass import Mass
    from ..ode.system import FirstOrderSystem, SecondOrderSystem, System

__all__ = ["NewtonOptions", "solve_stage"]


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
    if system.kind == "first_order":
        return _solve_first_order(system, t_star, base[0], theta_h, options)  # type: ignore[arg-type]
    return _solve_second_order(system, t_star, base, theta_h, options)  # type: ignore[arg-type]


def _solve_first_order(
    system: FirstOrderSystem, t: float, y_base: np.ndarray, theta_h: float, options: NewtonOptions
) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
    y = y_base.copy()
    iteration, norm = 0, np.inf
    while iteration < options.max_iterations:
        iteration += 1
        rate = system.rhs(t, y)
        residual = y - y_base - theta_h * rate
        jacobian = system.jacobian(t, y, rate)
        update = _linear_solve(system, _identity_minus(jacobian, theta_h, y.shape), -residual)
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
    iteration, norm = 0, np.inf
    while iteration < options.max_iterations:
        iteration += 1
        q = q_base + theta_h * v
        force = system.force(t, q, v)
        momentum_change = v - v_base if mass is None else mass.apply(v - v_base)
        residual = momentum_change - theta_h * force
        stiffness, damping = system.force_jacobian(t, q, v, force)
        matrix = _mass_minus(mass, damping, stiffness, theta_h, v.shape)
        update = _linear_solve(system, matrix, -residual)
        v += update
        system.counters.newton_iterations += 1
        norm = _update_norm(update, v, options)
        if norm <= 1.0:
            return (q_base + theta_h * v, v), (v - v_base) / theta_h
        if not np.isfinite(norm):
            break
    raise _failure(t, iteration, norm)


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


def _identity_minus(jacobian: Any, theta_h: float, shape: tuple[int, ...]) -> Any:
    """``I − θh J`` in the storage of ``J`` (dense, batched dense or sparse)."""
    import scipy.sparse as sp

    if sp.issparse(jacobian):
        return (sp.identity(shape[-1], format="csc") - theta_h * jacobian).tocsc()
    return np.eye(shape[-1]) - theta_h * np.asarray(jacobian)


def _mass_minus(
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


def _linear_solve(system: System, matrix: Any, rhs: np.ndarray) -> np.ndarray:
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
