"""Momentum and energy helpers, checked on systems whose invariants are known exactly."""

import numpy as np
import pytest

import visviva as vv

MASSES = np.array([3.0, 1.0, 0.5])


def _three_bodies():
    """Planar gravity (G = 1) between three bodies, q = (x1, y1, x2, y2, x3, y3).

    Pair forces are equal and opposite and central, so total momentum and angular momentum are
    conserved by the exact flow — and exactly (to round-off) by velocity Verlet, whose kicks
    apply those same pair forces and whose drifts are free motion.
    """

    def force(t, q):
        x = q.reshape(-1, 3, 2)
        f = np.zeros_like(x)
        for i in range(3):
            for j in range(i + 1, 3):
                r = x[..., j, :] - x[..., i, :]
                d3 = (np.sum(r * r, axis=-1, keepdims=True) + 0.01) ** 1.5  # softened
                pull = MASSES[i] * MASSES[j] * r / d3
                f[..., i, :] += pull
                f[..., j, :] -= pull
        return f.reshape(q.shape)

    q0 = np.array([0.0, 0.0, 1.0, 0.0, -0.5, 0.8])
    v0 = np.array([0.0, -0.1, 0.0, 1.2, 0.4, -0.3])
    return vv.ode.SecondOrderProblem.from_force(force, np.repeat(MASSES, 2), q0, v0)


def test_verlet_conserves_momentum_and_angular_momentum_to_round_off():
    solution = vv.solve(_three_bodies(), "velocity_verlet", dt=1e-3, until=5.0, record_every=50)
    x = solution.q.reshape(-1, 3, 2)
    v = solution.v.reshape(-1, 3, 2)
    momentum = vv.analysis.linear_momentum(MASSES, v)
    angular = vv.analysis.angular_momentum(MASSES, x, v)
    scale = np.abs(MASSES[:, None] * v[0]).sum()
    np.testing.assert_allclose(momentum - momentum[0], 0.0, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(angular - angular[0], 0.0, rtol=0, atol=1e-12 * abs(angular[0]))
    # The bodies did move: the test is not passing on a frozen state.
    assert np.abs(x[-1] - x[0]).max() > 0.5


def test_centre_of_mass_moves_uniformly():
    """With no external force the centre of mass moves at the constant velocity P / M."""
    solution = vv.solve(_three_bodies(), "leapfrog", dt=1e-3, until=2.0, record_every=100)
    centre = vv.analysis.center_of_mass(MASSES, solution.q.reshape(-1, 3, 2))
    velocity = vv.analysis.linear_momentum(MASSES, solution.v[0].reshape(3, 2)) / MASSES.sum()
    np.testing.assert_allclose(centre, centre[0] + solution.t[:, None] * velocity, atol=1e-12)


def test_angular_momentum_of_a_point_in_three_dimensions():
    """L = m r × v for one particle: r = x̂, v = ŷ, m = 2 → L = 2ẑ."""
    L = vv.analysis.angular_momentum([2.0], [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    np.testing.assert_array_equal(L, [0.0, 0.0, 2.0])


def test_relative_change_and_drift():
    energy = np.array([2.0, 2.2, 1.9, 2.1])
    np.testing.assert_allclose(vv.analysis.relative_change(energy), [0, 0.1, -0.05, 0.05])
    recording = vv.Recording(np.arange(4.0), {"energy": energy})
    assert vv.analysis.energy_drift(recording) == pytest.approx(0.05)
    assert vv.analysis.max_energy_error(recording) == pytest.approx(0.1)
    zero = vv.Recording(np.arange(2.0), {"energy": np.array([0.0, 1.0])})
    assert vv.analysis.energy_drift(zero) is None


def test_shapes_are_checked():
    with pytest.raises(vv.ModelError, match="N = 2 masses"):
        vv.analysis.linear_momentum([1.0, 2.0], np.zeros((3, 2)))
