"""Particle forces tested against physics: every Jacobian against finite differences of the same
force, every conservative force's F = −∇U, closed forms of each law, and the assembled sparse
Jacobian against the dense finite-difference one."""

import numpy as np
import pytest

import visviva as vv
from visviva.forces import (
    Attractor,
    Damping,
    Drag,
    ForceSum,
    Gravitation,
    QuadraticDrag,
    Targets,
    UniformGravity,
    Vortex,
)

N = 7
RNG = np.random.default_rng(11)
X = RNG.normal(size=(N, 3))
V = RNG.normal(size=(N, 3))
MASS = RNG.uniform(0.5, 2.0, size=N)
SOME = Targets(N, [0, 2, 3, 6])


def _forces():
    """Every field, on all particles and on a subset."""
    return {
        "gravity": UniformGravity((0.0, -9.81, 0.0), MASS),
        "drag": Drag(0.7, MASS, SOME),
        "wind": Drag(0.4, MASS, air_velocity=(3.0, 0.0, -1.0)),
        "quadratic_drag": QuadraticDrag(0.3, MASS, SOME, air_velocity=(1.0, 2.0, 0.0)),
        "damping": Damping(0.5, MASS),
        "attractor": Attractor((0.2, 0.1, -0.3), 2.5, MASS, softening=0.2),
        "repulsor": Attractor((1.0, 0.0, 0.0), -1.0, MASS, SOME, softening=0.5),
        "vortex": Vortex((0.0, 0.0, 0.0), (0.0, 1.0, 0.3), 4.0, 0.8, MASS, core_radius=0.4),
        "gravitation": Gravitation(MASS, G=1.0, softening=0.1),
    }


def _force(force, x, v):
    out = np.zeros((N, 3))
    force.accumulate(0.0, x, v, out)
    return out


def _dense_jacobians(force_sum, x, v):
    """Dense (∂F/∂x, ∂F/∂v) by central differences of the same force, 3N × 3N."""
    step = 1e-6
    dfdx = np.zeros((3 * N, 3 * N))
    dfdv = np.zeros((3 * N, 3 * N))
    for column in range(3 * N):
        shift = np.zeros(3 * N)
        shift[column] = step
        shift = shift.reshape(N, 3)
        for matrix, plus, minus in (
            (dfdx, (x + shift, v), (x - shift, v)),
            (dfdv, (x, v + shift), (x, v - shift)),
        ):
            difference = _sum(force_sum, *plus) - _sum(force_sum, *minus)
            matrix[:, column] = difference.ravel() / (2 * step)
    return dfdx, dfdv


def _sum(force_sum, x, v):
    out = np.zeros((N, 3))
    force_sum.accumulate(0.0, x, v, out)
    return out


@pytest.mark.parametrize("name", [n for n in _forces() if n != "gravitation"])
def test_jacobian_matches_finite_differences_of_the_same_force(name):
    force = _forces()[name]
    total = ForceSum([force], N)
    assert total.has_jacobian
    analytic_x, analytic_v = total.jacobian(0.0, X, V)
    numeric_x, numeric_v = _dense_jacobians(total, X, V)
    scale = max(1.0, np.abs(numeric_x).max(), np.abs(numeric_v).max())
    np.testing.assert_allclose(analytic_x.toarray(), numeric_x, atol=1e-7 * scale)
    if analytic_v is None:
        assert not force.velocity_dependent
        np.testing.assert_allclose(numeric_v, 0.0, atol=1e-7 * scale)
    else:
        np.testing.assert_allclose(analytic_v.toarray(), numeric_v, atol=1e-7 * scale)


def test_summed_jacobian_of_all_fields_matches_finite_differences():
    """Blocks of several forces on the same particles land in the same slots and add up."""
    forces = [f for n, f in _forces().items() if n != "gravitation"]
    total = ForceSum(forces, N)
    assert total.blocks == N  # one diagonal block per particle, shared by every field
    analytic_x, analytic_v = total.jacobian(0.0, X, V)
    numeric_x, numeric_v = _dense_jacobians(total, X, V)
    np.testing.assert_allclose(analytic_x.toarray(), numeric_x, atol=1e-6)
    np.testing.assert_allclose(analytic_v.toarray(), numeric_v, atol=1e-6)


@pytest.mark.parametrize("name", ["gravity", "attractor", "repulsor", "gravitation"])
def test_conservative_force_is_minus_the_gradient_of_its_potential(name):
    """F_i = −∂U/∂x_i, by central differences of the reported potential energy."""
    force = _forces()[name]
    assert force.conservative
    step = 1e-6
    gradient = np.zeros((N, 3))
    for i in range(N):
        for axis in range(3):
            shift = np.zeros((N, 3))
            shift[i, axis] = step
            up = force.potential(0.0, X + shift)
            down = force.potential(0.0, X - shift)
            gradient[i, axis] = (up - down) / (2 * step)
    np.testing.assert_allclose(_force(force, X, V), -gradient, atol=1e-6)


def test_dissipative_fields_report_no_potential_and_are_not_conservative():
    for name in ("drag", "wind", "quadratic_drag", "damping", "vortex"):
        force = _forces()[name]
        assert not force.conservative
        assert force.potential(0.0, X) == 0.0


def test_closed_forms_of_the_laws():
    gravity = _force(_forces()["gravity"], X, V)
    np.testing.assert_allclose(gravity, MASS[:, None] * [0.0, -9.81, 0.0], rtol=1e-15)
    # Wind: F = −k (v − w) on every particle.
    wind = _force(_forces()["wind"], X, V)
    np.testing.assert_allclose(wind, -0.4 * (V - [3.0, 0.0, -1.0]), rtol=1e-14)
    # Drag on a subset only.
    drag = _force(_forces()["drag"], X, V)
    np.testing.assert_allclose(drag[SOME.indices], -0.7 * V[SOME.indices], rtol=1e-14)
    assert not drag[[1, 4, 5]].any()
    # Quadratic drag: |F| = c |u|², opposite to u.
    u = V - [1.0, 2.0, 0.0]
    quadratic = _force(_forces()["quadratic_drag"], X, V)[SOME.indices]
    speeds = np.linalg.norm(u[SOME.indices], axis=1)
    np.testing.assert_allclose(np.linalg.norm(quadratic, axis=1), 0.3 * speeds**2, rtol=1e-13)
    # Damping: −γ m v.
    np.testing.assert_allclose(
        _force(_forces()["damping"], X, V), -0.5 * MASS[:, None] * V, rtol=1e-14
    )


def test_attractor_is_newtons_inverse_square_far_from_its_softening():
    """|F| = s m / r² for r ≫ ε, towards the centre."""
    force = Attractor((0.0, 0.0, 0.0), 3.0, np.array([2.0]), softening=1e-4)
    x = np.array([[10.0, 0.0, 0.0]])
    f = _force_one(force, x)
    np.testing.assert_allclose(f, [[-3.0 * 2.0 / 100.0, 0.0, 0.0]], rtol=1e-9)


def _force_one(force, x):
    out = np.zeros_like(x)
    force.accumulate(0.0, x, np.zeros_like(x), out)
    return out


def test_vortex_air_turns_like_a_line_vortex_outside_its_core():
    """Air speed Γ/(2π r) tangential at distance r ≫ core; a particle moving with the air
    feels no force."""
    gamma, r, core = 5.0, 3.0, 1e-3
    force = Vortex((0, 0, 0), (0, 1, 0), gamma, 1.0, np.ones(1), core_radius=core)
    x = np.array([[r, 7.0, 0.0]])  # any height along the axis
    air = gamma / (2 * np.pi * r)
    core_effect = air * (core / r) ** 2  # u = Γ/(2π) r/(r² + core²): relative error core²/r²
    # Counter-clockwise about +Y: at +X the air moves towards −Z.
    moving_with_air = np.array([[0.0, 0.0, -air]])
    out = np.zeros((1, 3))
    force.accumulate(0.0, x, moving_with_air, out)
    np.testing.assert_allclose(out, 0.0, atol=1.01 * core_effect)
    out = np.zeros((1, 3))
    force.accumulate(0.0, x, np.zeros((1, 3)), out)
    np.testing.assert_allclose(out, [[0.0, 0.0, -air]], atol=1.01 * core_effect)


def test_gravitation_pairs_cancel_and_match_the_mechanics_kernel():
    force = _forces()["gravitation"]
    f = _force(force, X, V)
    np.testing.assert_allclose(f.sum(axis=0), 0.0, atol=1e-13 * np.abs(f).sum())
    expected = MASS[:, None] * vv.mechanics.gravity_accelerations(X, MASS, G=1.0, softening=0.1)
    np.testing.assert_allclose(f, expected, rtol=1e-12)
    assert force.jacobian_blocks() is None
    assert not ForceSum([force, _forces()["drag"]], N).has_jacobian


def test_potential_counts_only_live_particles_when_asked():
    force = _forces()["attractor"]
    alive = np.zeros(N, dtype=bool)
    alive[[1, 5]] = True
    single = [
        Attractor((0.2, 0.1, -0.3), 2.5, MASS, Targets(N, [i]), softening=0.2) for i in (1, 5)
    ]
    expected = sum(f.potential(0.0, X) for f in single)
    assert force.potential(0.0, X, alive) == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize(
    "build, field",
    [
        (lambda: Drag(-1.0, MASS), "coefficient"),
        (lambda: Damping(float("nan"), MASS), "rate"),
        (lambda: Attractor((0, 0), 1.0, MASS), "point"),
        (lambda: Attractor((0, 0, 0), 1.0, MASS, softening=0.0), "softening"),
        (lambda: Vortex((0, 0, 0), (0, 0, 0), 1.0, 1.0, MASS), "axis"),
        (lambda: Drag(1.0, MASS, air_velocity=(1, 2, float("inf"))), "velocity"),
        (lambda: Gravitation(MASS, G=-1.0), "G"),
    ],
)
def test_bad_parameters_are_refused_with_the_field_named(build, field):
    with pytest.raises(vv.ModelError, match=f"`{field}`"):
        build()
