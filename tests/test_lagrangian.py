"""Lagrangian systems: derived equations against hand-derived ones, exact periods, Jacobians
against finite differences, both backends, energy under a symplectic method, bad input."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
import sympy
from scipy.special import ellipk

import visviva as vv
from visviva.errors import ModelError
from visviva.mechanics import classic

LagrangianSystem = vv.mechanics.LagrangianSystem
t = sympy.Symbol("t")
G = 9.81


def pendulum(length: float = 2.0) -> LagrangianSystem:
    m, L, g = sympy.symbols("m L g")
    theta = sympy.Function("theta")(t)
    return LagrangianSystem(
        [theta],
        kinetic=m * L**2 * theta.diff(t) ** 2 / 2,  # K = ½ m L² θ̇²
        potential=-m * g * L * sympy.cos(theta),  # U = −m g L cos θ
        parameters={"m": 1.5, "L": length, "g": G},
        name="pendulum",
    )


def double_pendulum(m1=1.0, m2=2.0, l1=1.0, l2=0.5) -> LagrangianSystem:
    """Written in Cartesian positions of the bobs, as a student would."""
    a, b = sympy.Function("theta1")(t), sympy.Function("theta2")(t)
    M1, M2, L1, L2, g = sympy.symbols("m1 m2 L1 L2 g")
    x1, y1 = L1 * sympy.sin(a), -L1 * sympy.cos(a)
    x2, y2 = x1 + L2 * sympy.sin(b), y1 - L2 * sympy.cos(b)
    kinetic = (
        M1 * (x1.diff(t) ** 2 + y1.diff(t) ** 2) / 2 + M2 * (x2.diff(t) ** 2 + y2.diff(t) ** 2) / 2
    )
    potential = M1 * g * y1 + M2 * g * y2
    values = {"m1": m1, "m2": m2, "L1": l1, "L2": l2, "g": G}
    return LagrangianSystem([a, b], kinetic, potential, parameters=values, name="double pendulum")


def double_pendulum_acceleration(q, v, m1=1.0, m2=2.0, l1=1.0, l2=0.5):
    """The textbook closed form of the double pendulum's accelerations."""
    a, b = q
    wa, wb = v
    delta = a - b
    den = 2 * m1 + m2 - m2 * math.cos(2 * delta)
    aa = (
        -G * (2 * m1 + m2) * math.sin(a)
        - m2 * G * math.sin(a - 2 * b)
        - 2 * math.sin(delta) * m2 * (wb**2 * l2 + wa**2 * l1 * math.cos(delta))
    ) / (l1 * den)
    ab = (
        2
        * math.sin(delta)
        * (wa**2 * l1 * (m1 + m2) + G * (m1 + m2) * math.cos(a) + wb**2 * l2 * m2 * math.cos(delta))
    ) / (l2 * den)
    return np.array([aa, ab])


# --- the derived equations -----------------------------------------------------------------


def test_pendulum_equation_is_the_textbook_one():
    (equation,) = pendulum().equations()
    theta = sympy.Function("theta")(t)
    m, L, g = sympy.symbols("m L g")
    # m L² θ̈ = −m g L sin θ
    assert sympy.simplify(equation.lhs - m * L**2 * theta.diff(t, 2)) == 0
    assert sympy.simplify(equation.rhs + m * g * L * sympy.sin(theta)) == 0
    assert "\\ddot{\\theta}" in pendulum().latex()
    assert pendulum().text() == "L**2*m*theta'' = -L*g*m*sin(theta)"


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_double_pendulum_matches_the_closed_form(backend):
    system = double_pendulum()
    rng = np.random.default_rng(1)
    q, v = rng.uniform(-2, 2, (8, 2)), rng.uniform(-3, 3, (8, 2))
    problem = system.problem(q, v, backend=backend)
    for i in range(8):
        out = np.empty(2)
        one = system.problem(q[i], v[i], backend=backend)
        one.force.func(0.0, q[i], v[i], out)
        np.testing.assert_allclose(
            out, double_pendulum_acceleration(q[i], v[i]), rtol=1e-12, atol=1e-12
        )
    assert problem.batch_size == 8 and system.velocity_dependent


def test_numpy_batch_and_numba_give_the_same_accelerations_and_energy():
    system = double_pendulum()
    rng = np.random.default_rng(2)
    q, v = rng.uniform(-2, 2, (5, 2)), rng.uniform(-3, 3, (5, 2))
    numpy_f = system.problem(q, v, backend="numpy").force.func
    numba_f = system.problem(q, v, backend="numba").force.func
    batch = np.empty((5, 2))
    numpy_f(0.0, q, v, batch)
    for i in range(5):
        one = np.empty(2)
        numba_f(0.0, q[i], v[i], one)
        np.testing.assert_allclose(one, batch[i], rtol=1e-13, atol=1e-13)
    # E = K + U for a kinetic energy quadratic in the velocities
    m1, m2, l1, l2 = 1.0, 2.0, 1.0, 0.5
    a, b = q[:, 0], q[:, 1]
    kinetic = 0.5 * (m1 + m2) * l1**2 * v[:, 0] ** 2 + 0.5 * m2 * l2**2 * v[:, 1] ** 2
    kinetic += m2 * l1 * l2 * v[:, 0] * v[:, 1] * np.cos(a - b)
    potential = -(m1 + m2) * G * l1 * np.cos(a) - m2 * G * l2 * np.cos(b)
    np.testing.assert_allclose(system.energy(q, v), kinetic + potential, rtol=1e-13)


def finite_difference(f, x, step=1e-6):
    """Central differences of f at x, one column per component of x (error O(step²))."""
    columns = []
    for k in range(x.size):
        e = np.zeros_like(x)
        e[k] = step
        columns.append((f(x + e) - f(x - e)) / (2 * step))
    return np.array(columns).T


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_jacobians_match_finite_differences(backend):
    system = double_pendulum()
    q, v = np.array([0.7, -1.2]), np.array([1.5, -0.4])
    problem = system.problem(q, v, backend=backend)
    jq, jv = problem.jacobian.func(0.0, q, v)

    def acceleration(qq, vv_):
        out = np.empty(2)
        problem.force.func(0.0, qq, vv_, out)
        return out

    # Central differences: truncation ~ step² |a'''| ≈ 1e-12, rounding ~ 1e-16/step ≈ 1e-10.
    np.testing.assert_allclose(jq, finite_difference(lambda x: acceleration(x, v), q), atol=1e-8)
    np.testing.assert_allclose(jv, finite_difference(lambda x: acceleration(q, x), v), atol=1e-8)


@pytest.mark.parametrize("backend", ["numpy", "numba"])
@pytest.mark.parametrize("which", ["double pendulum", "rotating frame"])
def test_canonical_jacobian_matches_finite_differences(backend, which):
    """Hamilton's f(q, p) and its analytic Jacobian: M(q) in the double pendulum, the offset
    b(q) in p = M q̇ + b for the rotating frame."""
    system = double_pendulum() if which == "double pendulum" else rotating_frame()
    problem = system.canonical_problem([0.7, -1.2], [1.5, -0.4], backend=backend)
    y = problem.y0

    def f(yy):
        out = np.empty(4)
        problem.f.func(0.0, yy, out)
        return out

    np.testing.assert_allclose(problem.jacobian.func(0.0, y), finite_difference(f, y), atol=1e-7)


def test_position_only_systems_get_position_only_functions():
    system = pendulum()
    assert not system.velocity_dependent
    problem = system.problem([0.3], [0.0])
    assert problem.force.state_arguments == 1
    jacobian = problem.jacobian.func(0.0, np.array([0.3]))
    # ∂θ̈/∂θ = −(g/L) cos θ
    np.testing.assert_allclose(jacobian, [[-G / 2.0 * math.cos(0.3)]], rtol=1e-14)


def test_explicit_time_dependence_drives_the_pendulum():
    """A pendulum whose pivot moves as y_p = A cos ωt: θ̈ = −(g + ÿ_p) sin θ / L."""
    m, L, g, A, w = sympy.symbols("m L g A omega")
    theta = sympy.Function("theta")(t)
    x, y = L * sympy.sin(theta), A * sympy.cos(w * t) - L * sympy.cos(theta)
    system = LagrangianSystem(
        [theta],
        m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2,
        m * g * y,
        parameters={"m": 1.0, "L": 1.0, "g": G, "A": 0.1, "omega": 20.0},
    )
    problem = system.problem([0.4], [0.5], backend="numpy")
    for time in (0.0, 0.3, 1.1):
        out = np.empty(1)
        problem.force.func(time, np.array([0.4]), np.array([0.5]), out)
        pivot = -0.1 * 20.0**2 * math.cos(20.0 * time)
        np.testing.assert_allclose(out, [-(G + pivot) * math.sin(0.4)], rtol=1e-13)


def rotating_frame() -> LagrangianSystem:
    """A free particle seen from a frame turning at Ω: K = ½ m ((ẋ − Ω y)² + (ẏ + Ω x)²)."""
    x, y, vx, vy, m, omega = sympy.symbols("x y v_x v_y m Omega")
    return LagrangianSystem(
        [x, y],
        m * ((vx - omega * y) ** 2 + (vy + omega * x) ** 2) / 2,
        velocities=[vx, vy],
        parameters={"m": 2.0, "Omega": 0.5},
    )


def test_velocity_terms_give_coriolis_and_centrifugal_forces():
    system = rotating_frame()
    q, v = np.array([1.0, -2.0]), np.array([0.3, 0.7])
    out = np.empty(2)
    system.problem(q, v, backend="numpy").force.func(0.0, q, v, out)
    # ẍ = 2Ω ẏ + Ω² x, ÿ = −2Ω ẋ + Ω² y
    np.testing.assert_allclose(out, [2 * 0.5 * 0.7 + 0.25 * 1.0, -2 * 0.5 * 0.3 + 0.25 * -2.0])
    # p = m (q̇ + Ω ẑ × q) and back
    p = system.momenta(q, v)
    np.testing.assert_allclose(p, 2.0 * (v + 0.5 * np.array([-q[1], q[0]])))
    np.testing.assert_allclose(system.velocities(q, p), v, rtol=1e-15)


def test_canonical_and_second_order_forms_agree():
    system = rotating_frame()
    q0, v0 = np.array([1.0, 0.0]), np.array([0.0, 0.2])
    second = vv.solve(system.problem(q0, v0), method="rk4", dt=1e-3, until=2.0)
    canonical = vv.solve(system.canonical_problem(q0, v0), method="rk4", dt=1e-3, until=2.0)
    # Same flow in other variables; both RK4 at h = 1e-3 (global error ~ h⁴ ≈ 1e-12).
    np.testing.assert_allclose(canonical.y[-1, :2], second.q[-1], atol=1e-10)
    # The Jacobi integral E = ½ m |q̇|² − ½ m Ω² |q|² is conserved by the exact flow.
    assert np.ptp(second.energy) < 1e-9


def test_damping_as_a_generalized_force():
    """m ẍ + c ẋ + k x = 0 with Q = −c ẋ, against the underdamped closed form."""
    x, vx, m, k, c = sympy.symbols("x v m k c")
    system = LagrangianSystem(
        [x],
        m * vx**2 / 2,
        k * x**2 / 2,
        velocities=[vx],
        forces=[-c * vx],
        parameters={"m": 1.0, "k": 4.0, "c": 0.4},
    )
    solution = vv.solve(system.problem([1.0], [0.0]), method="rk4", dt=1e-3, until=5.0)
    gamma, omega_d = 0.2, math.sqrt(4.0 - 0.04)
    exact = np.exp(-gamma * solution.t) * (
        np.cos(omega_d * solution.t) + gamma / omega_d * np.sin(omega_d * solution.t)
    )
    np.testing.assert_allclose(solution.q[:, 0], exact, atol=1e-11)  # RK4: ~h⁴ = 1e-12
    assert np.all(np.diff(solution.energy) <= 1e-15)  # dE/dt = −c ẋ² ≤ 0


# --- periods -------------------------------------------------------------------------------


def measured_period(solution: vv.Solution) -> float:
    return classic.oscillation_period(solution.t, solution.q[:, 0], solution.v[:, 0])


@pytest.mark.parametrize("theta0", [0.05, 1.0])
def test_pendulum_period_is_the_elliptic_integral(theta0):
    """T = 4 √(L/g) K(k²), k = sin(θ0/2); RK4's period error falls as h⁴."""
    length = 2.0
    exact = 4.0 * math.sqrt(length / G) * ellipk(math.sin(theta0 / 2) ** 2)
    system = pendulum(length)
    errors = []
    for dt in (0.04, 0.02):
        solution = vv.solve(system.problem([theta0], [0.0]), method="rk4", dt=dt, until=10 * exact)
        errors.append(abs(measured_period(solution) - exact) / exact)
    # Error of order h⁴ (the Hermite location is O(h⁴) too): halving h divides it by ~16.
    assert errors[1] < 2e-7
    assert 10 < errors[0] / errors[1] < 22
    if theta0 == 0.05:
        # Small angles: ω² = g/L, with the first correction T ≈ T0 (1 + θ0²/16).
        small = 2 * math.pi * math.sqrt(length / G)
        assert abs(exact / small - 1 - theta0**2 / 16) < theta0**4
        assert abs(measured_period(solution) / small - 1) < theta0**2 / 16 + 1e-6


# --- energy under a symplectic method ---------------------------------------------------------


def test_double_pendulum_energy_stays_bounded_under_implicit_midpoint():
    """Implicit midpoint is symplectic in (q, p): the energy error oscillates at O(h²) and does
    not grow, over a chaotic trajectory. Explicit Euler on the same problem gains energy.

    Measured on this trajectory: max |ΔE/E| = 0.113 at h = 0.01 and 0.0287 at h = 0.005 (ratio
    3.9 ≈ 2²), flat over 200 s in both cases."""
    system = double_pendulum()
    problem = system.canonical_problem([2.0, 1.0], [0.0, 0.0])
    solution = vv.solve(problem, method="implicit_midpoint", dt=0.01, until=100.0)
    error = np.abs(solution.energy - solution.energy[0]) / abs(solution.energy[0])
    tenth = error.size // 10
    assert error.max() < 0.15
    # No drift: the last tenth of the run is no worse than the first tenth (within 2×).
    assert error[-tenth:].max() < 2.0 * error[:tenth].max()
    euler = vv.solve(
        system.problem([2.0, 1.0], [0.0, 0.0]), method="explicit_euler", dt=0.01, until=20.0
    )
    assert euler.energy[-1] - euler.energy[0] > 10 * error.max() * abs(solution.energy[0])


# --- bad input ------------------------------------------------------------------------------


def refused(match: str, *args, **kwargs) -> None:
    with pytest.raises(ModelError, match=match):
        LagrangianSystem(*args, **kwargs)


def test_bad_descriptions_are_refused_with_the_problem_named():
    theta = sympy.Function("theta")(t)
    phi = sympy.Function("phi")(t)
    m, L = sympy.symbols("m L")
    kinetic = m * L**2 * theta.diff(t) ** 2 / 2
    refused("must be a SymPy expression", [theta], lambda q: q, 0)
    refused("symbols L, m", [theta], kinetic, 0)
    refused(
        "do not use.*Did you mean 'm'", [theta], kinetic, 0, parameters={"m": 1, "L": 1, "mm": 2}
    )
    refused(
        "`potential` depends on the velocities",
        [theta],
        kinetic,
        theta.diff(t) ** 2,
        parameters={"m": 1, "L": 1},
    )
    refused(
        "does not depend on the velocity of phi",
        [theta, phi],
        kinetic,
        sympy.cos(phi),
        parameters={"m": 1, "L": 1},
    )
    refused(
        "first time derivatives",
        [theta],
        kinetic + theta.diff(t, 2),
        0,
        parameters={"m": 1, "L": 1},
    )
    refused("mixes functions of time and plain symbols", [theta, sympy.Symbol("x")], kinetic)
    refused("need `velocities`", [sympy.Symbol("x")], sympy.Symbol("v") ** 2)
    refused("empty", [], kinetic)
    refused("must be finite", [theta], kinetic, 0, parameters={"m": float("nan"), "L": 1})
    refused(
        "one generalized force per coordinate",
        [theta],
        kinetic,
        0,
        parameters={"m": 1, "L": 1},
        forces=[0, 0],
    )


def test_singular_mass_matrix_at_the_initial_state():
    """Spherical coordinates at the pole: K = ½ m L² (θ̇² + sin²θ φ̇²) has M singular at θ = 0."""
    theta, phi = sympy.Function("theta")(t), sympy.Function("phi")(t)
    system = LagrangianSystem(
        [theta, phi],
        (theta.diff(t) ** 2 + sympy.sin(theta) ** 2 * phi.diff(t) ** 2) / 2,
    )
    with pytest.raises(ModelError, match=r"mass matrix M\(q0\) is singular.*q0 = \[0.0, 0.3\]"):
        system.problem([0.0, 0.3], [0.0, 1.0])
    system.problem([0.5, 0.3], [0.0, 1.0], backend="numpy")  # away from the pole it is fine


def test_bad_states_and_backend():
    system = pendulum()
    with pytest.raises(ModelError, match="`q0` must have 1 entries"):
        system.problem([0.1, 0.2], [0.0, 0.0])
    with pytest.raises(ModelError, match="Did you mean 'numba'"):
        system.problem([0.1], [0.0], backend="numbaa")
    with pytest.raises(ModelError, match="q0"):
        system.problem([float("inf")], [0.0])


# ---------------------------------------------------------------- compiled once per machine

_BUILD_TWICE = """
import visviva as vv
system = vv.mechanics.classic.double_pendulum()
problem = system.problem([1.0, 0.5], [0.0, 0.0])
functions = [f.func for f in (problem.force, problem.jacobian, problem.energy) if f is not None]
solution = vv.solve(problem, "rk4", dt=0.01, until=0.5)
hits = sum(sum(f.stats.cache_hits.values()) for f in functions)
print(hits, repr(float(solution.q[-1, 1])))
"""


def run_fresh(tmp_path, cache) -> tuple[int, str]:
    import subprocess
    import sys

    environment = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    done = subprocess.run(
        [sys.executable, "-c", _BUILD_TWICE],
        capture_output=True,
        text=True,
        env=environment,
        cwd=tmp_path,
        timeout=600,
        check=True,
    )
    hits, last = done.stdout.split()
    return int(hits), last


def test_generated_equations_compile_once_per_machine(tmp_path):
    # The second process loads the machine code the first compiled: the same numbers, no
    # compilation (Numba counts a cache hit per function loaded).
    cache = tmp_path / "cache"
    first_hits, first = run_fresh(tmp_path, cache)
    assert first_hits == 0 and list((cache / "visviva-equations").glob("*.py"))
    again_hits, again = run_fresh(tmp_path, cache)
    assert again_hits >= 2 and again == first
    # A cache that cannot be written: compiled in memory, the same numbers.
    blocked = tmp_path / "blocked"
    blocked.write_text("a file where the cache directory would be")
    assert run_fresh(tmp_path, blocked) == (0, first)
