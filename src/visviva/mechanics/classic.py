"""The classic systems of seeds 001 and 004, written once as energies, with their exact answers.

Every system is a :class:`~visviva.mechanics.LagrangianSystem` built from ``K`` and ``U`` exactly
as the notes write them (positions of the bodies first, then their speeds squared), with the
bodies' positions as ``points`` so that recordings can be drawn. World frame: ``x`` to the
right, ``y`` up, pivots at the origin, SI units. Where a closed form exists it is here too, so
tests and demos compare against it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import sympy

from .._validation import real_number
from ..errors import ModelError
from ..ode.problems import SecondOrderProblem
from .lagrangian import LagrangianSystem

__all__ = [
    "LAGRANGIAN_SYSTEMS",
    "STANDARD_GRAVITY",
    "constrained_pendulum",
    "damped_oscillator",
    "damped_oscillator_solution",
    "double_pendulum",
    "oscillation_period",
    "pendulum",
    "pendulum_period",
    "rock",
    "rock_trajectory",
    "small_angle_pendulum",
    "spring_pendulum",
]

#: Standard gravity g_n [m/s²] (CGPM 1901, exact by definition).
STANDARD_GRAVITY = 9.80665

_t = sympy.Symbol("t")


def _speed_squared(*coordinates: sympy.Expr) -> sympy.Expr:
    return sum((c.diff(_t) ** 2 for c in coordinates), sympy.Integer(0))


def _positive(name: str, value: float, unit: str) -> float:
    return real_number(name, value, positive=True, unit=unit)


def rock(*, mass: float = 1.0, g: float = STANDARD_GRAVITY) -> LagrangianSystem:
    """Seed 001's thrown rock: a point mass in 3-D under uniform gravity, ``U = m g y``.

    Coordinates ``(x, y, z)`` [m]; the exact motion is :func:`rock_trajectory`.
    """
    m, gravity = sympy.symbols("m g")
    x, y, z = (sympy.Function(name)(_t) for name in "xyz")
    return LagrangianSystem(
        [x, y, z],
        kinetic=m * _speed_squared(x, y, z) / 2,
        potential=m * gravity * y,
        parameters={"m": _positive("mass", mass, " kg"), "g": real_number("g", g)},
        points=[(x, y, z)],
        name="rock",
    )


def rock_trajectory(t: Any, q0: Any, v0: Any, g: float = STANDARD_GRAVITY) -> np.ndarray:
    """The parabola ``x(t) = x0 + v0 t − ½ g t² ŷ`` [m], shape ``t.shape + (3,)``."""
    t = np.asarray(t, dtype=float)[..., None]
    return np.asarray(q0) + np.asarray(v0) * t - 0.5 * g * np.array([0.0, 1.0, 0.0]) * t**2


def pendulum(
    *, length: float = 1.0, mass: float = 1.0, g: float = STANDARD_GRAVITY
) -> LagrangianSystem:
    """The pendulum of seed 001: ``K = ½ m L² θ̇²``, ``U = −m g L cos θ``, θ from straight down.

    Points: the pivot (at the origin) and the bob, joined by the rod.
    """
    m, L, gravity = sympy.symbols("m L g")
    theta = sympy.Function("theta")(_t)
    bob = (L * sympy.sin(theta), -L * sympy.cos(theta))
    return LagrangianSystem(
        [theta],
        kinetic=m * L**2 * theta.diff(_t) ** 2 / 2,
        potential=-m * gravity * L * sympy.cos(theta),
        parameters={
            "m": _positive("mass", mass, " kg"),
            "L": _positive("length", length, " m"),
            "g": _positive("g", g, " m/s²"),
        },
        points=[(0, 0), bob],
        edges=[(0, 1)],
        name="pendulum",
    )


def pendulum_period(amplitude: float, *, length: float = 1.0, g: float = STANDARD_GRAVITY) -> float:
    """Exact period [s] of a pendulum released from rest at ``amplitude`` [rad] (< π).

    ``T = 4 √(L/g) K(k)``, ``k = sin(θ0/2)``, with ``K`` the complete elliptic integral of the
    first kind (SciPy's ``ellipk`` takes the parameter ``m = k²``).
    """
    from scipy.special import ellipk

    theta0 = abs(real_number("amplitude", amplitude, unit=" rad"))
    if not theta0 < math.pi:
        raise ModelError(
            f"`amplitude` must be below π (got {amplitude!r}): a pendulum released at the top "
            "never swings back, its period is infinite"
        )
    root = math.sqrt(_positive("length", length, " m") / _positive("g", g, " m/s²"))
    return 4.0 * root * float(ellipk(math.sin(theta0 / 2.0) ** 2))


def oscillation_period(t: Any, q: Any, v: Any) -> float:
    """Mean period [s] of a recorded oscillation of ``q`` about 0 (upward zero crossings).

    Each crossing between two frames is located on the cubic Hermite interpolant through
    ``(q, q̇)`` at both frames (error O(h⁴), the order of RK4), so the measurement does not
    limit the accuracy of the method measured. Needs at least two crossings.
    """
    t, q, v = (np.asarray(a, dtype=float) for a in (t, q, v))
    crossings = []
    for i in np.flatnonzero((q[:-1] < 0) & (q[1:] >= 0)):
        h = t[i + 1] - t[i]
        q0, q1, d0, d1 = q[i], q[i + 1], h * v[i], h * v[i + 1]
        s = -q0 / (q1 - q0)  # the secant's root, then Newton on the cubic
        for _ in range(8):
            value = (
                (2 * s**3 - 3 * s**2 + 1) * q0
                + (s**3 - 2 * s**2 + s) * d0
                + (-2 * s**3 + 3 * s**2) * q1
                + (s**3 - s**2) * d1
            )
            slope = (
                (6 * s**2 - 6 * s) * q0
                + (3 * s**2 - 4 * s + 1) * d0
                + (-6 * s**2 + 6 * s) * q1
                + (3 * s**2 - 2 * s) * d1
            )
            s -= value / slope
        crossings.append(t[i] + s * h)
    if len(crossings) < 2:
        raise ModelError(
            f"the recording crosses zero upward {len(crossings)} time(s); a period needs two: "
            "record a longer run"
        )
    return float(np.mean(np.diff(crossings)))


def small_angle_pendulum(
    t: Any, theta0: float, omega0: float = 0.0, *, length: float = 1.0, g: float = STANDARD_GRAVITY
) -> np.ndarray:
    """The small-angle solution ``θ(t) = θ0 cos ωt + (θ̇0/ω) sin ωt``, ``ω² = g/L`` [rad]."""
    omega = math.sqrt(g / length)
    t = np.asarray(t, dtype=float)
    return theta0 * np.cos(omega * t) + omega0 / omega * np.sin(omega * t)


def double_pendulum(
    *,
    masses: tuple[float, float] = (1.0, 1.0),
    lengths: tuple[float, float] = (1.0, 1.0),
    g: float = STANDARD_GRAVITY,
) -> LagrangianSystem:
    """Two pendulums end to end (seed 001's "not-so-simple example"), angles from the vertical.

    ``K`` and ``U`` are written from the bobs' Cartesian positions; the Euler–Lagrange
    equations carry the coupling ``m₂ L₁ L₂ cos(θ₁ − θ₂)`` and the chaos with it.
    """
    m1, m2, l1, l2, gravity = sympy.symbols("m1 m2 L1 L2 g")
    a, b = sympy.Function("theta1")(_t), sympy.Function("theta2")(_t)
    x1, y1 = l1 * sympy.sin(a), -l1 * sympy.cos(a)
    x2, y2 = x1 + l2 * sympy.sin(b), y1 - l2 * sympy.cos(b)
    values = {
        "m1": _positive("masses[0]", masses[0], " kg"),
        "m2": _positive("masses[1]", masses[1], " kg"),
        "L1": _positive("lengths[0]", lengths[0], " m"),
        "L2": _positive("lengths[1]", lengths[1], " m"),
        "g": _positive("g", g, " m/s²"),
    }
    return LagrangianSystem(
        [a, b],
        kinetic=m1 * _speed_squared(x1, y1) / 2 + m2 * _speed_squared(x2, y2) / 2,
        potential=m1 * gravity * y1 + m2 * gravity * y2,
        parameters=values,
        points=[(0, 0), (x1, y1), (x2, y2)],
        edges=[(0, 1), (1, 2)],
        name="double pendulum",
    )


def spring_pendulum(
    *,
    mass: float = 1.0,
    stiffness: float = 40.0,
    rest_length: float = 1.0,
    g: float = STANDARD_GRAVITY,
) -> LagrangianSystem:
    """A bob on a spring swinging under gravity, in polar coordinates ``(r, θ)``.

    ``K = ½ m (ṙ² + r² θ̇²)``, ``U = ½ k (r − L₀)² − m g r cos θ``. The spring's and the
    swing's motions exchange energy (strongly near ω_spring = 2 ω_swing).
    """
    m, k, rest, gravity = sympy.symbols("m k L0 g")
    r, theta = sympy.Function("r")(_t), sympy.Function("theta")(_t)
    return LagrangianSystem(
        [r, theta],
        kinetic=m * (r.diff(_t) ** 2 + r**2 * theta.diff(_t) ** 2) / 2,
        potential=k * (r - rest) ** 2 / 2 - m * gravity * r * sympy.cos(theta),
        parameters={
            "m": _positive("mass", mass, " kg"),
            "k": _positive("stiffness", stiffness, " N/m"),
            "L0": _positive("rest_length", rest_length, " m"),
            "g": _positive("g", g, " m/s²"),
        },
        points=[(0, 0), (r * sympy.sin(theta), -r * sympy.cos(theta))],
        edges=[(0, 1)],
        name="spring pendulum",
    )


def damped_oscillator(
    *, mass: float = 1.0, stiffness: float = 4.0, damping: float = 0.4
) -> LagrangianSystem:
    """``m ẍ + c ẋ + k x = 0``: ``K = ½ m ẋ²``, ``U = ½ k x²`` and the force ``Q = −c ẋ``.

    Drawn as a mass on a spring from a wall at ``x = −1.5 m``; the exact motion is
    :func:`damped_oscillator_solution`. Without damping there is no force ``Q``: the equations
    then depend on positions only, which symplectic methods need to be symplectic (and which
    saves velocity Verlet an evaluation per step).
    """
    m, k, c = sympy.symbols("m k c")
    x = sympy.Function("x")(_t)
    friction = real_number("damping", damping, nonnegative=True, unit=" N·s/m")
    parameters = {
        "m": _positive("mass", mass, " kg"),
        "k": _positive("stiffness", stiffness, " N/m"),
    }
    if friction > 0.0:
        parameters["c"] = friction
    return LagrangianSystem(
        [x],
        kinetic=m * x.diff(_t) ** 2 / 2,
        potential=k * x**2 / 2,
        forces=[-c * x.diff(_t)] if friction > 0.0 else [0],
        parameters=parameters,
        points=[(-1.5, 0), (x, 0)],
        edges=[(0, 1)],
        name="damped oscillator",
    )


def damped_oscillator_solution(
    t: Any, x0: float, v0: float, *, mass: float = 1.0, stiffness: float = 4.0, damping: float = 0.4
) -> np.ndarray:
    """Exact ``x(t)`` [m] of ``m ẍ + c ẋ + k x = 0`` for every damping regime.

    With ``γ = c/2m`` and ``ω0² = k/m``: ``x = e^{−γt}(x0 C(t) + (v0 + γ x0) S(t))`` where
    ``C = cos ωt, S = sin(ωt)/ω`` (ω² = ω0² − γ² > 0), ``cosh``/``sinh`` when overdamped and
    ``C = 1, S = t`` at critical damping.
    """
    t = np.asarray(t, dtype=float)
    gamma = damping / (2.0 * mass)
    discriminant = stiffness / mass - gamma**2
    if discriminant > 0:
        omega = math.sqrt(discriminant)
        c, s = np.cos(omega * t), np.sin(omega * t) / omega
    elif discriminant < 0:
        omega = math.sqrt(-discriminant)
        c, s = np.cosh(omega * t), np.sinh(omega * t) / omega
    else:
        c, s = np.ones_like(t), t
    return np.exp(-gamma * t) * (x0 * c + (v0 + gamma * x0) * s)


def constrained_pendulum(
    theta0: float,
    omega0: float = 0.0,
    *,
    length: float = 1.0,
    mass: float = 1.0,
    g: float = STANDARD_GRAVITY,
    stabilization_rate: float = 0.0,
) -> tuple[SecondOrderProblem, Any]:
    """The pendulum as a free particle ``r = (x, y)`` held by a constraint force, not by θ.

    The rod keeps ``C(r) = ½(|r − c|² − L²) = 0`` (pivot ``c`` at the origin) with the force
    ``f^c = λ (r − c)`` along it. Asking ``C̈ = 0`` gives the multiplier in closed form,

        λ = −m (|ṙ|² + (r − c)·g) / |r − c|²,

    so ``m r̈ = m g + λ (r − c)`` is an ordinary second-order problem. Numerically ``C`` drifts;
    ``stabilization_rate = α > 0`` asks for ``C̈ = −2α Ċ − α² C`` instead (Baumgarte 1972, critically
    damped), pulling the particle back onto the circle at the rate α [1/s].

    Args:
        theta0, omega0: Initial angle from straight down [rad] and angular velocity [rad/s].
        length, mass, g: Rod length [m], bob mass [kg], gravity [m/s²].
        stabilization_rate: Baumgarte rate α [1/s]; 0 for the pure index-reduced equations.

    Returns:
        The problem on ``q = (x, y)`` (energy ``½ m |ṙ|² + m g y``) and
        ``multiplier(q, v) -> λ`` [N/m], so the constraint force ``λ (r − c)`` can be plotted.
    """
    length = _positive("length", length, " m")
    mass = _positive("mass", mass, " kg")
    g = _positive("g", g, " m/s²")
    alpha = real_number("stabilization_rate", stabilization_rate, nonnegative=True, unit=" 1/s")
    gravity = np.array([0.0, -g])

    def multiplier(q: np.ndarray, v: np.ndarray) -> Any:
        distance2 = np.sum(q * q, axis=-1)
        constraint = 0.5 * (distance2 - length**2)  # C
        rate = np.sum(q * v, axis=-1)  # Ċ = (r − c)·ṙ
        # C̈ = (r − c)·r̈ + |ṙ|² with r̈ = g + λ(r − c)/m, set equal to −2αĊ − α²C:
        wanted = -2.0 * alpha * rate - alpha**2 * constraint
        return mass * (wanted - np.sum(v * v, axis=-1) - q @ gravity) / distance2

    def acceleration(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return gravity + multiplier(q, v)[..., None] * q / mass

    def energy(t: float, q: np.ndarray, v: np.ndarray) -> Any:
        return 0.5 * mass * np.sum(v * v, axis=-1) + mass * g * q[..., 1]

    theta0 = real_number("theta0", theta0, unit=" rad")
    omega0 = real_number("omega0", omega0, unit=" rad/s")
    q0 = length * np.array([math.sin(theta0), -math.cos(theta0)])
    v0 = length * omega0 * np.array([math.cos(theta0), math.sin(theta0)])
    problem = SecondOrderProblem(
        acceleration, q0, v0, energy=energy, name="pendulum as a constrained particle"
    )
    return problem, multiplier


#: The classic Lagrangian systems by their scene and command-line names, each with its defaults
#: (``visviva equations NAME`` prints their equations of motion).
LAGRANGIAN_SYSTEMS: dict[str, Callable[[], LagrangianSystem]] = {
    "rock": rock,
    "pendulum": pendulum,
    "double-pendulum": double_pendulum,
    "spring-pendulum": spring_pendulum,
    "damped-oscillator": damped_oscillator,
}
