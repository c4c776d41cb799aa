"""Stability functions measured by running a method on linear test problems.

For a method on a general state, ``R(z)`` is the result of one step of size ``h = 1`` on the
test equation ``y' = λy`` from ``y = 1`` with ``λ = z`` (seeds 000 and 004: explicit Euler gives
``1 + z``, backward Euler ``1/(1 − z)``). Complex ``y`` lets one batched run evaluate ``R`` at
thousands of points.

A method on the split ``(q, v)`` state of ``q'' = F`` cannot be applied to a scalar ``y' = λy``.
It is applied instead to the scalar oscillator ``q'' = α q + β v`` whose characteristic roots
are ``λ`` and ``conj(λ)`` (``α = −|λ|²``, ``β = 2 Re λ``; ``λ = ±iω`` is the undamped spring of
seed 000). One step is then a 2 × 2 amplification matrix; ``R(z)`` is its eigenvalue of largest
modulus (on a tie, the one in the half plane of ``z``), which is what decides growth. For
methods that also apply to first-order problems both definitions agree, because Runge–Kutta
methods commute with linear changes of variables.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..ode.state import Layout, State
from ..ode.system import Structure, WorkCounters
from ..ode.workspace import Workspace

if TYPE_CHECKING:
    from .base import Integrator

__all__ = ["measured_stability_function"]


class _TestEquation(Structure):
    """``y' = λ y`` for a batch of complex ``λ`` (one per system, ``n = 1``)."""

    second_order = False
    has_energy = False

    def __init__(self, lam: np.ndarray) -> None:
        self.lam = lam[:, None]
        self.counters = WorkCounters()
        self.workspace = Workspace()

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        return self.lam * y

    def derivative(self, t: float, parts: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
        return (self.rhs(t, parts[0]),)

    def jacobian(self, t: float, y: np.ndarray, rate: Any = None) -> np.ndarray:
        return self.lam[:, :, None].copy()


class _TestOscillator(Structure):
    """``q'' = α q + β v`` for a batch of complex ``(α, β)`` (one per system, ``n = 1``)."""

    second_order = True
    has_energy = False
    mass = None
    velocity_dependent = True

    def __init__(self, alpha: np.ndarray, beta: np.ndarray) -> None:
        self.alpha = alpha[:, None]
        self.beta = beta[:, None]
        self.counters = WorkCounters()
        self.workspace = Workspace()

    def force(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return self.alpha * q + self.beta * v

    acceleration = force

    def derivative(self, t: float, parts: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
        q, v = parts
        return (v, self.force(t, q, v))

    def force_jacobian(self, t: float, q: Any, v: Any, force: Any = None) -> tuple[Any, Any]:
        return self.alpha[:, :, None].copy(), self.beta[:, :, None].copy()


def measured_stability_function(method: Integrator, z: Any) -> np.ndarray:
    """``R(z)`` of ``method`` measured with one step of ``h = 1`` (see the module docstring)."""
    z = np.asarray(z, dtype=np.complex128)
    flat = z.ravel()
    if flat.size == 0:
        return np.empty(z.shape, dtype=np.complex128)
    if not method.second_order_only:
        system = _TestEquation(flat)
        y0 = np.ones((flat.size, 1), dtype=np.complex128)
        state = method.step(system, State(0.0, (y0,), Layout.first_order()), 1.0)  # type: ignore[arg-type]
        return np.asarray(state.parts[0][:, 0]).reshape(z.shape)

    alpha = -(np.abs(flat) ** 2)
    beta = 2.0 * flat.real
    system2 = _TestOscillator(np.tile(alpha, 2), np.tile(beta, 2))
    ones = np.ones(flat.size, dtype=np.complex128)
    zeros = np.zeros(flat.size, dtype=np.complex128)
    # Two columns of the amplification matrix: start from (q, v) = (1, 0) and from (0, 1).
    q0 = np.concatenate([ones, zeros])[:, None]
    v0 = np.concatenate([zeros, ones])[:, None]
    state2 = method.step(system2, State(0.0, (q0, v0), Layout.positions_and_velocities()), 1.0)  # type: ignore[arg-type]
    q1, v1 = (np.asarray(part)[:, 0] for part in state2.parts)
    m = flat.size
    amplification = np.empty((m, 2, 2), dtype=np.complex128)
    amplification[:, 0, 0], amplification[:, 1, 0] = q1[:m], v1[:m]
    amplification[:, 0, 1], amplification[:, 1, 1] = q1[m:], v1[m:]
    eigenvalues = np.linalg.eigvals(amplification)
    modulus = np.abs(eigenvalues)
    # Dominant eigenvalue; between a conjugate pair of equal modulus, the one on z's side.
    side = np.sign(flat.imag)[:, None] * np.sign(eigenvalues.imag)
    rank = modulus * (1.0 + 1e-12 * side)
    chosen = eigenvalues[np.arange(m), np.argmax(rank, axis=1)]
    return chosen.reshape(z.shape)
