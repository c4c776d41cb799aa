"""Problems with exact solutions, for measuring accuracy (tests, ``visviva convergence``).

Each is chosen to catch a particular mistake: the pendulum is nonlinear (its exact motion uses
Jacobi elliptic functions); the forced oscillator's force depends on time, so a method that
evaluates stages at the wrong time loses order; the damped oscillator's force depends on
velocity, which costs careless kick–drift methods an order; the first-order system is nonlinear
and time-dependent, for the methods' first-order code paths.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._registry import Registry
from ..ode.problems import FirstOrderProblem, Problem, SecondOrderProblem

__all__ = ["ReferenceProblem", "reference_problem", "reference_problems"]


@dataclass(frozen=True)
class ReferenceProblem:
    """A problem and its exact solution.

    Attributes:
        name: Short name (``visviva convergence --problem NAME``).
        description: One line.
        problem: The problem.
        exact: ``exact(t)`` → ``(y,)`` or ``(q, v)`` at time ``t``.
    """

    name: str
    description: str
    problem: Problem
    exact: Callable[[float], tuple[np.ndarray, ...]]


def _pendulum(theta0: float = 1.0, omega: float = 1.0) -> ReferenceProblem:
    """``θ'' = −ω² sin θ`` released at rest from ``θ0``.

    With ``k = sin(θ0/2)`` and ``K`` the complete elliptic integral of the first kind,
    ``θ(t) = 2 arcsin(k sn(K − ωt, k))`` and ``θ'(t) = −2kω cn(K − ωt, k)``.
    """
    from scipy.special import ellipj, ellipk

    k = np.sin(theta0 / 2.0)
    quarter = ellipk(k**2)

    def exact(t: float) -> tuple[np.ndarray, ...]:
        sn, cn, _, _ = ellipj(quarter - omega * t, k**2)
        return np.array([2.0 * np.arcsin(k * sn)]), np.array([-2.0 * k * omega * cn])

    problem = SecondOrderProblem(
        lambda t, q: -(omega**2) * np.sin(q),
        q0=[theta0],
        v0=[0.0],
        jacobian=lambda t, q: (-(omega**2) * np.cos(q))[..., None],
        energy=lambda t, q, v: 0.5 * v[..., 0] ** 2 + omega**2 * (1.0 - np.cos(q[..., 0])),
        name=f"pendulum, theta0 = {theta0} rad",
    )
    return ReferenceProblem(
        "pendulum", "pendulum θ'' = -sin θ from θ0 = 1 rad (elliptic functions)", problem, exact
    )


def _forced() -> ReferenceProblem:
    """``q'' = −q + cos 2t`` from rest at ``q = 1``: ``q = (4/3) cos t − (1/3) cos 2t``."""

    def exact(t: float) -> tuple[np.ndarray, ...]:
        return (
            np.array([4 / 3 * np.cos(t) - np.cos(2 * t) / 3]),
            np.array([-4 / 3 * np.sin(t) + 2 / 3 * np.sin(2 * t)]),
        )

    problem = SecondOrderProblem(
        lambda t, q: -q + np.cos(2.0 * t),
        q0=[1.0],
        v0=[0.0],
        name="forced oscillator q'' = -q + cos 2t",
    )
    return ReferenceProblem("forced", "time-dependent force q'' = -q + cos 2t", problem, exact)


def _damped(omega: float = 2.0, zeta: float = 0.1) -> ReferenceProblem:
    """``q'' = −ω²q − 2ζω q'`` from ``q = 1`` at rest (underdamped closed form)."""
    decay = zeta * omega
    omega_d = omega * np.sqrt(1.0 - zeta**2)

    def exact(t: float) -> tuple[np.ndarray, ...]:
        envelope = np.exp(-decay * t)
        c, s = np.cos(omega_d * t), np.sin(omega_d * t)
        q = envelope * (c + decay / omega_d * s)
        v = -envelope * (omega**2 / omega_d) * s
        return np.array([q]), np.array([v])

    problem = SecondOrderProblem(
        lambda t, q, v: -(omega**2) * q - 2.0 * zeta * omega * v,
        q0=[1.0],
        v0=[0.0],
        jacobian=lambda t, q, v: (
            np.full(q.shape + (1,), -(omega**2)),
            np.full(q.shape + (1,), -2.0 * zeta * omega),
        ),
        name="damped oscillator",
    )
    return ReferenceProblem("damped", "velocity-dependent force q'' = -4q - 0.4q'", problem, exact)


def _first_order() -> ReferenceProblem:
    """The pendulum as a first-order system plus a driven decay, ``y = (θ, θ', z)``.

    ``θ'' = −sin θ`` from 1 rad at rest (as :func:`_pendulum`) and ``z' = −z + cos t`` from
    ``z = 1``, whose solution is ``z = (cos t + sin t)/2 + e^{−t}/2``: nonlinear and
    time-dependent at once.
    """
    pendulum = _pendulum()

    def f(t: float, y: np.ndarray) -> np.ndarray:
        return np.stack([y[..., 1], -np.sin(y[..., 0]), np.cos(t) - y[..., 2]], axis=-1)

    def jacobian(t: float, y: np.ndarray) -> np.ndarray:
        matrix = np.zeros(y.shape + (3,))
        matrix[..., 0, 1] = 1.0
        matrix[..., 1, 0] = -np.cos(y[..., 0])
        matrix[..., 2, 2] = -1.0
        return matrix

    def exact(t: float) -> tuple[np.ndarray, ...]:
        (theta,), (rate,) = pendulum.exact(t)
        z = 0.5 * (np.cos(t) + np.sin(t)) + 0.5 * np.exp(-t)
        return (np.array([theta, rate, z]),)

    problem = FirstOrderProblem(
        f,
        [1.0, 0.0, 1.0],
        jacobian=jacobian,
        name="pendulum as a first-order system, plus z' = -z + cos t",
    )
    return ReferenceProblem(
        "first-order", "first-order pendulum plus driven decay z' = -z + cos t", problem, exact
    )


@dataclass(frozen=True)
class _Builder:
    """How to build the reference problem called ``name``."""

    name: str
    build: Callable[..., ReferenceProblem]


_BUILDERS: Registry[_Builder] = Registry("reference problem")
for _name, _build in (
    ("pendulum", _pendulum),
    ("forced", _forced),
    ("damped", _damped),
    ("first-order", _first_order),
):
    _BUILDERS.register(_Builder(_name, _build))
del _name, _build


def reference_problems() -> list[str]:
    """Names of the reference problems."""
    return _BUILDERS.names()


def reference_problem(name: str, **parameters: Any) -> ReferenceProblem:
    """Build the reference problem ``name`` (see :func:`reference_problems`).

    Raises:
        ModelError: For an unknown name; the message lists the valid names.
    """
    return _BUILDERS.get(name).build(**parameters)
