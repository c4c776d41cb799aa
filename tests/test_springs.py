"""Damped springs tested against physics: exact Jacobians against central finite differences of
the same force at many random configurations (compressed springs included), f = −∇U without
damping, forces that sum to zero, the damper that does not resist a rigid rotation, and bad
springs refused with the spring named."""

import numpy as np
import pytest

from visviva.errors import ModelError
from visviva.forces import ForceSum
from visviva.forces.springs import Springs

N = 6
PAIRS = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [0, 2], [1, 3], [5, 0], [2, 5]])


def _springs(rng, damping=True):
    springs = PAIRS.shape[0]
    return Springs(
        PAIRS,
        rest_length=rng.uniform(0.5, 2.0, springs),
        stiffness=rng.uniform(10.0, 200.0, springs),
        damping=rng.uniform(0.1, 3.0, springs) if damping else 0.0,
        count=N,
    )


def _force(force, x, v):
    out = np.zeros((N, 3))
    force.accumulate(0.0, x, v, out)
    return out


def _numeric_jacobians(force, x, v, step=1e-6):
    """Dense (∂F/∂x, ∂F/∂v) by central differences of the same force."""
    dfdx = np.zeros((3 * N, 3 * N))
    dfdv = np.zeros((3 * N, 3 * N))
    for column in range(3 * N):
        shift = np.zeros(3 * N)
        shift[column] = step
        shift = shift.reshape(N, 3)
        dfdx[:, column] = (_force(force, x + shift, v) - _force(force, x - shift, v)).ravel()
        dfdv[:, column] = (_force(force, x, v + shift) - _force(force, x, v - shift)).ravel()
    return dfdx / (2 * step), dfdv / (2 * step)


def test_jacobians_match_central_differences_at_100_random_configurations():
    rng = np.random.default_rng(4)
    compressed = 0
    for _ in range(100):
        springs = _springs(rng)
        x = rng.normal(scale=1.0, size=(N, 3))
        v = rng.normal(size=(N, 3))
        lengths = np.linalg.norm(x[PAIRS[:, 1]] - x[PAIRS[:, 0]], axis=1)
        compressed += int((lengths < springs.rest_length).sum())
        analytic_x, analytic_v = ForceSum([springs], N).jacobian(0.0, x, v)
        numeric_x, numeric_v = _numeric_jacobians(springs, x, v)
        # Relative to the largest entry: central differences are good to ~1e-9 here.
        for analytic, numeric in ((analytic_x, numeric_x), (analytic_v, numeric_v)):
            error = np.abs(analytic.toarray() - numeric).max() / np.abs(numeric).max()
            assert error <= 1e-6
    assert compressed > 100  # the indefinite, compressed case is well covered


def test_undamped_springs_are_minus_the_gradient_of_their_energy():
    rng = np.random.default_rng(5)
    springs = _springs(rng, damping=False)
    assert springs.conservative and not springs.velocity_dependent
    x = rng.normal(size=(N, 3))
    step = 1e-6
    gradient = np.zeros((N, 3))
    for i in range(N):
        for axis in range(3):
            shift = np.zeros((N, 3))
            shift[i, axis] = step
            gradient[i, axis] = (
                springs.potential(0.0, x + shift) - springs.potential(0.0, x - shift)
            ) / (2 * step)
    np.testing.assert_allclose(_force(springs, x, np.zeros((N, 3))), -gradient, atol=1e-6)


def test_internal_forces_sum_to_zero_and_a_rigid_rotation_is_not_damped():
    rng = np.random.default_rng(6)
    springs = _springs(rng)
    x = rng.normal(size=(N, 3))
    v = rng.normal(size=(N, 3))
    force = _force(springs, x, v)
    np.testing.assert_allclose(force.sum(axis=0), 0.0, atol=1e-12 * np.abs(force).max())
    # Net torque about the origin is zero too: each pair's forces lie along the spring.
    np.testing.assert_allclose(np.cross(x, force).sum(axis=0), 0.0, atol=1e-10)
    # A rigid rotation ω × x stretches no spring: the dampers add nothing.
    omega = np.array([0.3, -1.2, 0.7])
    at_rest = _force(springs, x, np.zeros((N, 3)))
    np.testing.assert_allclose(_force(springs, x, np.cross(omega, x)), at_rest, atol=1e-12)


def test_a_single_spring_obeys_hookes_law():
    # Stretched by 0.5 m with k = 40 N/m: 20 N pulling the ends together.
    spring = Springs(np.array([[0, 1]]), 1.5, 40.0, 0.0, 2)
    x = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    out = np.zeros((2, 3))
    spring.accumulate(0.0, x, np.zeros((2, 3)), out)
    np.testing.assert_allclose(out, [[20.0, 0.0, 0.0], [-20.0, 0.0, 0.0]])
    assert spring.potential(0.0, x) == pytest.approx(0.5 * 40.0 * 0.5**2)


def test_definite_projection_drops_only_the_compressed_springs_negative_part():
    rng = np.random.default_rng(7)
    x = rng.normal(size=(N, 3))
    v = np.zeros((N, 3))
    total = ForceSum([_springs(np.random.default_rng(8))], N)
    exact, projected = (total.jacobian(0.0, x, v, form)[0] for form in ("exact", "definite"))
    # −∂F/∂x is the stiffness matrix: positive semi-definite once projected, not before.
    assert np.linalg.eigvalsh(-projected.toarray()).min() > -1e-9
    assert np.linalg.eigvalsh(-exact.toarray()).min() < -1e-6


@pytest.mark.parametrize(
    ("pairs", "rest", "stiffness", "damping", "message"),
    [
        ([[0, 1], [1, 7]], 1.0, 1.0, 0.0, "spring 1 joins a particle that does not exist"),
        ([[0, 1], [2, 2]], 1.0, 1.0, 0.0, "spring 1 joins a particle to itself"),
        ([[0, 1]], 0.0, 1.0, 0.0, "spring 0 has a rest length that is not positive"),
        (
            [[0, 1], [1, 2]],
            1.0,
            [1.0, -2.0],
            0.0,
            "spring 1 has a negative or non-finite stiffness",
        ),
        ([[0, 1]], 1.0, 1.0, np.nan, "spring 0 has a negative or non-finite damping"),
        ([[0, 1]], [1.0, 2.0], 1.0, 0.0, "`rest_length` must be one number or one per spring"),
    ],
)
def test_bad_springs_are_refused_with_the_spring_named(pairs, rest, stiffness, damping, message):
    with pytest.raises(ModelError, match=message):
        Springs(np.array(pairs), rest, stiffness, damping, count=3)
