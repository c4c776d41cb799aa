"""The stability advisor: the largest stable step of a method for a system at a state.

The step limit comes from the eigenvalues of the linearization ``∂(dy/dt)/∂y`` (seed 000,
"Matrix eigenvalues"; :func:`~visviva.analysis.stability.max_stable_dt`). A small system, or
one with an analytic (possibly sparse) Jacobian, gets its Jacobian. A large system without one
never gets a matrix: the extreme eigenvalues come from ARPACK's implicitly restarted Arnoldi
iteration on Jacobian-vector products, each one forward difference of ``f``
(:func:`~visviva.ode.system.directional_difference`), so memory stays ``O(n)`` — a 20,000-star
cluster would need a 120,000² dense Jacobian (107 GiB) and 60,000 force evaluations.

For a second-order system whose force depends on positions only, ``y' = [v, M⁻¹F(q)]`` has
the Jacobian ``[[0, I], [A, 0]]`` with ``A = M⁻¹ ∂F/∂q``, whose eigenvalues are ``±√μ`` for the
eigenvalues ``μ`` of ``A``: the advisor works on ``A``, half the size and better conditioned.

References:
    R. B. Lehoucq, D. C. Sorensen, C. Yang, *ARPACK Users' Guide*, SIAM 1998.
    D. A. Knoll, D. E. Keyes, "Jacobian-free Newton–Krylov methods: a survey of approaches
    and applications", J. Comput. Phys. 193 (2004) 357–397.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..ode.system import FirstOrderSystem
from .stability import DENSE_EIGEN_LIMIT, max_stable_dt, state_jacobian

if TYPE_CHECKING:
    from ..integrators import Integrator
    from ..ode.state import State
    from ..ode.system import System

__all__ = ["largest_stable_step", "matrix_free_eigenvalues"]

#: Extreme eigenvalues the Arnoldi iteration looks for: the step limit is set by the largest
#: ones, and a few more tell oscillating modes from growing and decaying ones.
MATRIX_FREE_EIGEN_COUNT = 4
#: Their relative accuracy: the advisor needs two or three digits.
MATRIX_FREE_TOLERANCE = 1e-3
#: Arnoldi restarts before giving up (each costs about 2·count products, i.e. f-evaluations).
MATRIX_FREE_RESTARTS = 40


def largest_stable_step(system: System, method: Integrator, state: State) -> float:
    """The advisor's largest stable step [s] of ``method`` for ``system`` linearized at ``state``.

    ``inf`` if every step is stable, ``0`` if none is (explicit Euler on an undamped
    oscillation). Dense for small systems and analytic Jacobians, matrix-free otherwise.
    """
    size = state.parts[0].shape[-1]
    batched = state.parts[0].ndim == 2
    unknowns = size * len(state.parts)
    if system.has_jacobian or batched or unknowns <= DENSE_EIGEN_LIMIT:
        return max_stable_dt(method, jacobian=state_jacobian(system, state))
    lam = matrix_free_eigenvalues(system, state)
    # Arnoldi's eigenvalues carry a relative error of about its tolerance: a real part below it
    # cannot tell an undamped mode from a slightly damped or growing one. Count it undamped,
    # the more restrictive reading for explicit methods (a growing mode would set no limit).
    lam = np.where(np.abs(lam.real) <= MATRIX_FREE_TOLERANCE * np.abs(lam), 1j * lam.imag, lam)
    return max_stable_dt(method, eigenvalues=lam)


def matrix_free_eigenvalues(system: System, state: State) -> np.ndarray:
    """The extreme eigenvalues [1/s] of a single system's first-order Jacobian at ``state``,
    from Jacobian-vector products only (see the module docstring). A Jacobian whose products
    vanish (free particles under uniform gravity) gives ``[0]``."""
    from scipy.sparse.linalg import LinearOperator

    t = state.t
    if isinstance(system, FirstOrderSystem):
        (y,) = state.parts
        rate = system.rhs(t, y)
        first = system
        operator = LinearOperator(
            (y.size, y.size),
            matvec=lambda u: first.jacobian_product(t, y, u.ravel(), rate),
            dtype=np.float64,
        )
        return _extreme_eigenvalues(operator)
    q, v = state.parts
    force = system.force(t, q, v)
    mass = system.mass
    second = system

    def inverse_mass(f: np.ndarray) -> np.ndarray:
        return f if mass is None else mass.solve(f)

    n = q.size
    if not system.velocity_dependent:
        stiffness = LinearOperator(
            (n, n),
            matvec=lambda u: inverse_mass(second.force_product(t, q, v, u.ravel(), None, force)),
            dtype=np.float64,
        )
        mu = _extreme_eigenvalues(stiffness).astype(np.complex128)
        root = np.sqrt(mu)  # principal root; -root is an eigenvalue too
        return np.concatenate([root, -root])

    def first_order(u: np.ndarray) -> np.ndarray:
        u = u.ravel()
        dq, dv = u[:n], u[n:]
        change = second.force_product(t, q, v, dq, dv, force)
        return np.concatenate([dv, inverse_mass(change)])

    operator = LinearOperator((2 * n, 2 * n), matvec=first_order, dtype=np.float64)
    return _extreme_eigenvalues(operator)


def _extreme_eigenvalues(operator: Any) -> np.ndarray:
    """Largest-magnitude eigenvalues of a real operator; ``[0]`` if it maps to zero."""
    from scipy.sparse.linalg import ArpackNoConvergence, eigs

    m = operator.shape[0]
    # A fixed start: the same state gives the same advice to the last digit.
    start = np.random.default_rng(0).standard_normal(m)
    if not np.any(operator.matvec(start)):
        return np.zeros(1)
    try:
        return np.asarray(
            eigs(
                operator,
                k=min(MATRIX_FREE_EIGEN_COUNT, m - 2),
                which="LM",
                v0=start,
                tol=MATRIX_FREE_TOLERANCE,
                maxiter=MATRIX_FREE_RESTARTS,
                return_eigenvectors=False,
            )
        )
    except ArpackNoConvergence as partial:
        if len(partial.eigenvalues):
            return np.asarray(partial.eigenvalues)
        raise
