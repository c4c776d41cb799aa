"""Lyapunov exponents and the separation of nearby trajectories."""

from __future__ import annotations

import numpy as np
import pytest
import sympy

import visviva as vv
from visviva.errors import ModelError, SimulationError
from visviva.mechanics import classic

x, v = sympy.symbols("x v")


def test_saddle_has_exponent_one_and_the_oscillator_zero():
    """ẍ = x separates like e^t (λ = 1); ẍ = −x does not separate (λ = 0).

    The first interval's growth also carries the projection of δ0 on the unstable direction
    (log 1/√2 ≈ −0.35), so the estimate after t seconds is 1 − 0.35/t ± a little.
    """
    saddle = vv.mechanics.LagrangianSystem([x], v**2 / 2, -(x**2) / 2, velocities=[v])
    estimate = vv.analysis.lyapunov_exponent(
        saddle.problem([0.0], [0.0]), until=40.0, dt=1e-3, interval=0.5
    )
    assert abs(estimate.exponent - 1.0) < 0.02
    assert estimate.times.shape == estimate.running.shape == (80,)
    oscillator = vv.mechanics.LagrangianSystem([x], v**2 / 2, x**2 / 2, velocities=[v])
    estimate = vv.analysis.lyapunov_exponent(oscillator.problem([1.0], [0.0]), until=40.0, dt=1e-2)
    assert abs(estimate.exponent) < 1e-6


def test_double_pendulum_is_chaotic_at_high_energy_only():
    system = classic.double_pendulum()
    wild = vv.analysis.lyapunov_exponent(
        system.problem([2.0, 1.0], [0.0, 0.0]), until=60.0, dt=2e-3, interval=0.5
    )
    calm = vv.analysis.lyapunov_exponent(
        system.problem([0.1, 0.05], [0.0, 0.0]), until=60.0, dt=2e-3, interval=0.5
    )
    assert wild.exponent > 0.5  # measured ≈ 1.1 /s over 100 s
    assert calm.exponent < 0.1  # tends to 0 like log(t)/t
    t, distance = vv.analysis.separation(
        system.problem([2.0, 1.0], [0.0, 0.0]), delta=1e-9, until=15.0, dt=1e-3
    )
    assert t.shape == distance.shape == (15001,)
    assert distance[0] == pytest.approx(1e-9)
    assert distance[-1] > 1e-3  # a billionth of a radian grows to a visible difference


def test_any_problem_first_order_and_a_later_start():
    """The measures take any problem: y' = y from t0 = 2 s separates like e^(t − t0)."""
    growth = vv.ode.FirstOrderProblem(lambda t, y: y, [1.0], t0=2.0)
    t, distance = vv.analysis.separation(growth, delta=1e-6, until=3.0, dt=1e-2)
    assert t[0] == 2.0 and t[-1] == pytest.approx(3.0)
    np.testing.assert_allclose(distance, 1e-6 * np.exp(t - 2.0), rtol=1e-8)
    # RK4's growth per step is e^h to O(h^5); the round-off of y ≈ e^4 against δ0 = 1e-6 is
    # what is left.
    estimate = vv.analysis.lyapunov_exponent(growth, until=6.0, dt=1e-2, interval=0.5, delta=1e-6)
    assert estimate.exponent == pytest.approx(1.0, abs=1e-7)
    assert estimate.times[0] == 2.5 and estimate.times[-1] == 6.0


def test_bad_arguments():
    system = classic.pendulum()
    problem = system.problem([0.1], [0.0])
    with pytest.raises(ModelError, match="at least one `interval`"):
        vv.analysis.lyapunov_exponent(problem, until=0.1, dt=0.01, interval=1.0)
    with pytest.raises(ModelError, match="`delta` must be positive"):
        vv.analysis.separation(problem, delta=0.0, until=1.0, dt=0.01)
    with pytest.raises(ModelError, match="not a batch of 2"):
        vv.analysis.separation(system.problem([[0.1], [0.2]], [[0.0], [0.0]]), until=1.0, dt=0.01)
    with pytest.raises(ModelError, match="unknown integration method 'rk5'"):
        vv.analysis.lyapunov_exponent(problem, until=1.0, dt=0.01, method="rk5")


def test_a_blow_up_is_reported_with_its_time():
    """Explicit Euler far beyond its stable step: the trajectories overflow."""
    stiff = vv.ode.FirstOrderProblem(lambda t, y: -1e3 * y, [1.0])
    with pytest.raises(SimulationError, match="stopped being finite") as caught:
        vv.analysis.separation(stiff, until=10.0, dt=0.1, method="explicit_euler")
    assert 0.0 < caught.value.t <= 10.0
