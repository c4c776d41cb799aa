"""Lyapunov exponents and the separation of nearby trajectories."""

from __future__ import annotations

import pytest
import sympy

import visviva as vv
from visviva.errors import ModelError
from visviva.mechanics import chaos, classic

x, v = sympy.symbols("x v")


def test_saddle_has_exponent_one_and_the_oscillator_zero():
    """ẍ = x separates like e^t (λ = 1); ẍ = −x does not separate (λ = 0).

    The first interval's growth also carries the projection of δ0 on the unstable direction
    (log 1/√2 ≈ −0.35), so the estimate after t seconds is 1 − 0.35/t ± a little.
    """
    saddle = vv.mechanics.LagrangianSystem([x], v**2 / 2, -(x**2) / 2, velocities=[v])
    estimate = chaos.lyapunov_exponent(saddle, [0.0], [0.0], t_end=40.0, dt=1e-3, interval=0.5)
    assert abs(estimate.exponent - 1.0) < 0.02
    assert estimate.times.shape == estimate.running.shape == (80,)
    oscillator = vv.mechanics.LagrangianSystem([x], v**2 / 2, x**2 / 2, velocities=[v])
    estimate = chaos.lyapunov_exponent(oscillator, [1.0], [0.0], t_end=40.0, dt=1e-2)
    assert abs(estimate.exponent) < 1e-6


def test_double_pendulum_is_chaotic_at_high_energy_only():
    system = classic.double_pendulum()
    wild = chaos.lyapunov_exponent(
        system, [2.0, 1.0], [0.0, 0.0], t_end=60.0, dt=2e-3, interval=0.5
    )
    calm = chaos.lyapunov_exponent(
        system, [0.1, 0.05], [0.0, 0.0], t_end=60.0, dt=2e-3, interval=0.5
    )
    assert wild.exponent > 0.5  # measured ≈ 1.1 /s over 100 s
    assert calm.exponent < 0.1  # tends to 0 like log(t)/t
    _t, distance = chaos.separation(system, [2.0, 1.0], [0.0, 0.0], delta=1e-9, t_end=15.0, dt=1e-3)
    assert distance[0] == pytest.approx(1e-9)
    assert distance[-1] > 1e-3  # a billionth of a radian grows to a visible difference


def test_bad_arguments():
    system = classic.pendulum()
    with pytest.raises(ModelError, match="one state of 1 values"):
        chaos.lyapunov_exponent(system, [0.1, 0.2], [0.0], t_end=1.0, dt=0.01)
    with pytest.raises(ModelError, match="at least one `interval`"):
        chaos.lyapunov_exponent(system, [0.1], [0.0], t_end=0.1, dt=0.01, interval=1.0)
    with pytest.raises(ModelError, match="`delta` must be positive"):
        chaos.separation(system, [0.1], [0.0], delta=0.0, t_end=1.0, dt=0.01)
