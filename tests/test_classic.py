"""The classic systems against their exact solutions and against each other."""

from __future__ import annotations

import math

import numpy as np
import pytest

import visviva as vv
from visviva.errors import ModelError
from visviva.mechanics import classic

G = classic.STANDARD_GRAVITY


def test_rock_follows_the_parabola():
    """Constant force: velocity Verlet is exact (to rounding); explicit Euler's height error is
    exactly +½ g h t (its position lags the velocity by one step)."""
    q0, v0 = np.array([0.0, 1.0, 0.0]), np.array([3.0, 8.0, -1.0])
    problem = classic.rock(mass=0.5).problem(q0, v0)
    exact = lambda t: classic.rock_trajectory(t, q0, v0)  # noqa: E731
    verlet = vv.solve(problem, method="velocity_verlet", dt=0.01, until=1.5)
    np.testing.assert_allclose(verlet.q, exact(verlet.t), atol=1e-12)
    h = 0.01
    euler = vv.solve(problem, method="explicit_euler", dt=h, until=1.5)
    error = euler.q[:, 1] - exact(euler.t)[:, 1]
    np.testing.assert_allclose(error, 0.5 * G * h * euler.t, atol=1e-12)


def test_reduced_and_constrained_pendulums_agree():
    """θ from the Lagrangian pendulum and atan2(x, −y) of the constrained particle: the same
    motion, both RK4 at h = 1e-3 (global error ~h⁴)."""
    theta0, length = 1.2, 0.8
    reduced = vv.solve(
        classic.pendulum(length=length).problem([theta0], [0.0]), method="rk4", dt=1e-3, until=5.0
    )
    for alpha in (0.0, 20.0):
        problem, multiplier = classic.constrained_pendulum(
            theta0, length=length, stabilization_rate=alpha
        )
        particle = vv.solve(problem, method="rk4", dt=1e-3, until=5.0)
        x, y = particle.q[:, 0], particle.q[:, 1]
        np.testing.assert_allclose(np.arctan2(x, -y), reduced.q[:, 0], atol=1e-7)
        drift = np.abs(np.hypot(x, y) - length).max()
        assert drift < 1e-9
        # The rod's tension: λ(r − c) along the rod, |λ| L = m (g cos θ + L θ̇²) for m = 1.
        theta, omega = reduced.q[:, 0], reduced.v[:, 0]
        tension = np.abs(multiplier(particle.q, particle.v)) * length
        np.testing.assert_allclose(tension, G * np.cos(theta) + length * omega**2, atol=1e-5)


def test_baumgarte_pulls_a_drifted_particle_back_to_the_circle():
    """Started 1 cm off the circle, the unstabilised particle keeps its error; with α = 20/s the
    error decays like (1 + αt) e^{−αt} (critical damping)."""
    problem, _ = classic.constrained_pendulum(0.5, stabilization_rate=20.0)
    off = vv.ode.SecondOrderProblem(
        problem.force.func, problem.q0 * 1.01, problem.v0, energy=problem.energy.func
    )
    solution = vv.solve(off, method="rk4", dt=1e-3, until=1.0)
    radius = np.hypot(solution.q[:, 0], solution.q[:, 1])
    assert abs(radius[0] - 1.01) < 1e-12 and abs(radius[-1] - 1.0) < 1e-6


def test_spring_pendulum_equations_and_energy():
    system = classic.spring_pendulum(mass=2.0, stiffness=50.0, rest_length=1.0)
    q, v = np.array([1.2, 0.4]), np.array([0.3, -0.7])
    out = np.empty(2)
    problem = system.problem(q, v)
    problem.force.func(0.0, q, v, out)
    r, theta = q
    rdot, thetadot = v
    # r̈ = r θ̇² − (k/m)(r − L0) + g cos θ;  θ̈ = −(2 ṙ θ̇ + g sin θ)/r
    expected = [
        r * thetadot**2 - 25.0 * (r - 1.0) + G * math.cos(theta),
        -(2 * rdot * thetadot + G * math.sin(theta)) / r,
    ]
    np.testing.assert_allclose(out, expected, rtol=1e-13)
    solution = vv.solve(problem, method="rk4", dt=1e-3, until=10.0)
    assert np.ptp(solution.energy) / abs(solution.energy[0]) < 1e-9  # RK4 drift ~ h⁴ per unit time


@pytest.mark.parametrize("damping", [0.4, 4.0, 10.0])  # under-, critically and over-damped
def test_damped_oscillator_matches_every_regime(damping):
    system = classic.damped_oscillator(mass=1.0, stiffness=4.0, damping=damping)
    solution = vv.solve(system.problem([1.0], [0.5]), method="rk4", dt=1e-3, until=4.0)
    exact = classic.damped_oscillator_solution(
        solution.t, 1.0, 0.5, mass=1.0, stiffness=4.0, damping=damping
    )
    np.testing.assert_allclose(solution.q[:, 0], exact, atol=1e-10)


def test_pendulum_period_limits_and_errors():
    small = 2 * math.pi * math.sqrt(2.0 / G)
    assert classic.pendulum_period(1e-6, length=2.0) == pytest.approx(small, rel=1e-12)
    # T(θ0) = T0 (1 + θ0²/16 + 11 θ0⁴/3072 + …)
    assert classic.pendulum_period(0.3, length=2.0) == pytest.approx(
        small * (1 + 0.3**2 / 16 + 11 * 0.3**4 / 3072), rel=1e-5
    )
    with pytest.raises(ModelError, match="below π"):
        classic.pendulum_period(math.pi)
    with pytest.raises(ModelError, match="`length` must be positive"):
        classic.pendulum(length=0.0)
    with pytest.raises(ModelError, match=r"`masses\[1\]`"):
        classic.double_pendulum(masses=(1.0, -1.0))


def test_small_angle_solution_is_the_linearised_motion():
    theta = classic.pendulum(length=1.0)
    solution = vv.solve(theta.problem([1e-3], [0.0]), method="rk4", dt=1e-3, until=3.0)
    linear = classic.small_angle_pendulum(solution.t, 1e-3, length=1.0)
    # The neglected sin θ − θ ≈ θ³/6 shifts the phase by ~θ0²/16 per radian: ~1e-7 · ω t · θ0.
    np.testing.assert_allclose(solution.q[:, 0], linear, atol=1e-9)


def test_points_are_where_the_bodies_are():
    system = classic.double_pendulum(lengths=(1.0, 0.5))
    q = np.array([[0.0, 0.0], [math.pi / 2, math.pi]])
    points = system.points(q)
    np.testing.assert_allclose(points[0], [[0, 0, 0], [0, -1, 0], [0, -1.5, 0]], atol=1e-15)
    np.testing.assert_allclose(points[1], [[0, 0, 0], [1, 0, 0], [1, 0.5, 0]], atol=1e-15)
    assert system.edges == ((0, 1), (1, 2))


def test_cli_prints_the_derived_equations():
    from typer.testing import CliRunner

    from visviva.cli.main import app

    result = CliRunner().invoke(app, ["equations", "spring-pendulum"])
    assert result.exit_code == 0
    # m r̈ = m r θ̇² − k (r − L0) + m g cos θ ;  m r² θ̈ = −m r (g sin θ + 2 ṙ θ̇)
    assert result.stdout.splitlines() == [
        "m*r'' = L0*k + g*m*cos(theta) - k*r + m*r*theta'**2",
        "m*r**2*theta'' = -m*(g*sin(theta) + 2*r'*theta')*r",
    ]
    latex = CliRunner().invoke(app, ["equations", "pendulum", "--latex"]).stdout
    assert "\\ddot{\\theta}" in latex
