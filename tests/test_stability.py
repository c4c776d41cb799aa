"""Linear stability: the test equation, stability functions, intervals and the step advisor."""

import math

import numpy as np
import pytest
import scipy.sparse as sp

import visviva as vv
from visviva.integrators.linear_test import measured_stability_function

INF = math.inf
SQRT8 = 2.0 * math.sqrt(2.0)


def _dopri5_imaginary_limit():
    """Where |R(iy)| first exceeds 1, from DOPRI5's polynomial R(z) = Σ_{k≤5} z^k/k! + z^6/600.

    Independent of the library: |R(iy)|² − 1 is a polynomial in y; take its smallest positive
    real root.
    """
    coefficients = [1, 1, 1 / 2, 1 / 6, 1 / 24, 1 / 120, 1 / 600]  # R(z) in rising powers
    r = np.polynomial.Polynomial(coefficients)
    # R(iy) = a(y) + i b(y) with real polynomials a, b.
    a = np.polynomial.Polynomial([c * (1j**k).real for k, c in enumerate(coefficients)])
    b = np.polynomial.Polynomial([c * (1j**k).imag for k, c in enumerate(coefficients)])
    assert abs(r(0.3j) - (a(0.3) + 1j * b(0.3))) < 1e-15
    roots = (a * a + b * b - 1).roots()
    positive = sorted(x.real for x in roots if abs(x.imag) < 1e-9 and x.real > 1e-6)
    return positive[0]


#: (method, real interval, imaginary interval), from the literature or closed forms.
KNOWN_INTERVALS = [
    ("explicit_euler", (-2.0, 0.0), (0.0, 0.0)),  # |1 + z| ≤ 1
    ("midpoint", (-2.0, 0.0), (0.0, 0.0)),  # |1 + z + z²/2| ≤ 1
    ("heun", (-2.0, 0.0), (0.0, 0.0)),
    ("rk4", (-2.785293563, 0.0), (-SQRT8, SQRT8)),
    ("dopri5", (-3.306543, 0.0), (-_dopri5_imaginary_limit(), _dopri5_imaginary_limit())),
    ("kutta3", (-2.512745327, 0.0), (-math.sqrt(3.0), math.sqrt(3.0))),
    ("symplectic_euler", None, (-2.0, 2.0)),  # trace of the amplification matrix: 2 − (ωh)²
    ("symplectic_euler_position_first", None, (-2.0, 2.0)),
    ("velocity_verlet", None, (-2.0, 2.0)),
    ("leapfrog", None, (-2.0, 2.0)),
    ("backward_euler", (-INF, 0.0), (-INF, INF)),  # |1/(1 − z)| ≤ 1 outside the unit disc at 1
    ("trapezoidal", (-INF, 0.0), (-INF, INF)),  # |(1 + z/2)/(1 − z/2)| ≤ 1 for Re z ≤ 0
    ("implicit_midpoint", (-INF, 0.0), (-INF, INF)),
]


@pytest.mark.parametrize(
    ("method", "real", "imaginary"), KNOWN_INTERVALS, ids=[c[0] for c in KNOWN_INTERVALS]
)
def test_stability_intervals_match_known_values(method, real, imaginary):
    """Computed intervals agree with the known ones to 1e-3."""
    if real is not None:
        np.testing.assert_allclose(vv.analysis.stability_interval(method, "real"), real, atol=1e-3)
    np.testing.assert_allclose(
        vv.analysis.stability_interval(method, "imaginary"), imaginary, atol=1e-3
    )


@pytest.mark.parametrize(
    "method", [m for m in vv.integrators.names() if not vv.integrators.get(m).second_order_only]
)
def test_declared_stability_function_matches_the_method(method):
    """R(z) from the tableau equals one measured step of y' = λy with h = 1, λ = z."""
    rng = np.random.default_rng(0)
    z = rng.uniform(-4, 2, 200) + 1j * rng.uniform(-4, 4, 200)
    integrator = vv.integrators.get(method)
    declared = integrator.stability_function(z)
    measured = measured_stability_function(integrator, z)
    np.testing.assert_allclose(measured, declared, rtol=1e-9, atol=1e-12)


def test_closed_forms_of_the_seed_methods():
    """Seeds 000/004: explicit Euler 1 + z, backward Euler 1/(1 − z), trapezoidal
    (1 + z/2)/(1 − z/2), RK4 the degree-4 Taylor polynomial of e^z."""
    z = np.array([-0.5 + 0.3j, 0.2j, -3.0, 1.5 - 2j])
    np.testing.assert_allclose(vv.analysis.stability_function("explicit_euler", z), 1 + z)
    np.testing.assert_allclose(vv.analysis.stability_function("backward_euler", z), 1 / (1 - z))
    np.testing.assert_allclose(
        vv.analysis.stability_function("trapezoidal", z), (1 + z / 2) / (1 - z / 2)
    )
    np.testing.assert_allclose(
        vv.analysis.stability_function("rk4", z), 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24
    )


def test_trapezoidal_keeps_modulus_one_on_the_imaginary_axis():
    """|R(iy)| = 1 for every y: an undamped linear mode keeps its amplitude."""
    y = np.linspace(-1e3, 1e3, 10001)
    np.testing.assert_allclose(
        np.abs(vv.analysis.stability_function("trapezoidal", 1j * y)), 1.0, rtol=0, atol=1e-14
    )


def _test_equation(lam):
    return vv.ode.FirstOrderProblem(
        lambda t, y: lam * y, [1.0], jacobian=lambda t, y: np.full((1, 1), lam)
    )


@pytest.mark.parametrize("lam", [-1.0, -10.0, -250.0])
def test_explicit_euler_stable_exactly_below_two_over_lambda(lam):
    """y' = λy, λ < 0: bounded for dt < 2/|λ| (|1 + hλ| < 1), growing above (seed 000)."""
    limit = 2.0 / abs(lam)
    stable = vv.solve(_test_equation(lam), "explicit_euler", dt=0.95 * limit, until=200 * limit)
    unstable = vv.solve(_test_equation(lam), "explicit_euler", dt=1.05 * limit, until=210 * limit)
    assert np.abs(stable.y).max() <= 1.0 and abs(stable.y[-1, 0]) < 1e-4
    # 1 + hλ = −1.1: 200 steps multiply y by exactly (−1.1)^200.
    assert len(unstable.t) == 201
    np.testing.assert_allclose(unstable.y[-1, 0], 1.1**200, rtol=1e-9)


@pytest.mark.parametrize("dt", [0.01, 0.5, 1.9, 2.1, 10.0, 1e4])
def test_backward_euler_decays_for_every_step(dt):
    """λ = −3: y_n = (1 + 3h)^−n decays monotonically for any h (A-stability)."""
    solution = vv.solve(_test_equation(-3.0), "backward_euler", dt=dt, until=20 * dt)
    assert np.all(np.diff(np.abs(solution.y[:, 0])) < 0)
    np.testing.assert_allclose(solution.y[-1, 0], (1 + 3 * dt) ** -20, rtol=1e-9)


def test_backward_euler_decays_where_the_exact_solution_grows():
    """Seed 000's caveat: y' = +y grows like e^t, but backward Euler with h > 2 decays, since
    |1/(1 − h)| < 1 — stability is not accuracy."""
    solution = vv.solve(_test_equation(1.0), "backward_euler", dt=3.0, until=30.0)
    np.testing.assert_allclose(solution.y[:, 0], (-0.5) ** np.arange(11), rtol=1e-9)
    growing = vv.solve(_test_equation(1.0), "backward_euler", dt=0.5, until=5.0)
    np.testing.assert_allclose(growing.y[-1, 0], 2.0**10, rtol=1e-9)


def test_max_stable_dt_for_a_decaying_mode():
    """Explicit Euler on λ = −100: 2/100; RK4: 2.785/100; backward Euler: unlimited."""
    assert vv.analysis.max_stable_dt("explicit_euler", eigenvalues=[-100.0]) == pytest.approx(
        0.02, rel=1e-9
    )
    assert vv.analysis.max_stable_dt("rk4", eigenvalues=[-100.0]) == pytest.approx(
        0.02785293563, rel=1e-6
    )
    assert vv.analysis.max_stable_dt("backward_euler", eigenvalues=[-100.0]) == INF


def test_max_stable_dt_for_an_oscillator_from_its_jacobian():
    """Spring k/m = ω², first-order Jacobian [[0, 1], [−ω², 0]], λ = ±iω: symplectic Euler
    and Verlet are limited by ωh ≤ 2, RK4 by 2√2, explicit Euler never stable (seed 000)."""
    omega = 7.0
    jacobian = np.array([[0.0, 1.0], [-(omega**2), 0.0]])
    assert vv.analysis.max_stable_dt("velocity_verlet", jacobian=jacobian) == pytest.approx(
        2 / omega, rel=1e-6
    )
    assert vv.analysis.max_stable_dt("symplectic_euler", jacobian=jacobian) == pytest.approx(
        2 / omega, rel=1e-6
    )
    assert vv.analysis.max_stable_dt("rk4", jacobian=jacobian) == pytest.approx(
        SQRT8 / omega, rel=1e-6
    )
    assert vv.analysis.max_stable_dt("explicit_euler", jacobian=jacobian) == 0.0
    assert vv.analysis.max_stable_dt("implicit_midpoint", jacobian=jacobian) == INF


def test_max_stable_dt_ignores_growing_and_zero_modes():
    """Modes that grow in the exact solution, and zero modes, impose no limit."""
    dt = vv.analysis.max_stable_dt("explicit_euler", eigenvalues=[0.0, 5.0, -4.0])
    assert dt == pytest.approx(0.5, rel=1e-9)
    assert vv.analysis.max_stable_dt("rk4", eigenvalues=[0.0, 3.0]) == INF


def _chain_stiffness(n, k=1.0):
    """Stiffness K of n unit masses joined by springs k, both ends fixed.

    Its eigenvalues are −ω_j² with ω_j² = 4k sin²(jπ/2(n+1)).
    """
    main = np.full(n, -2.0 * k)
    off = np.full(n - 1, k)
    return sp.diags([off, main, off], [-1, 0, 1], format="csr")


def test_max_stable_dt_of_a_large_sparse_system():
    """A 3000-mass chain (6000 × 6000 sparse Jacobian) uses the Arnoldi solver for the extreme
    eigenvalues: Verlet's limit is 2/ω_max with ω_max = 2 sin(nπ/(2(n+1))).

    ARPACK stops at a residual ‖Jx − θx‖ ≤ tol·|θ|; for this non-symmetric J (eigenvectors
    (x, iωx), condition ~ max(ω, 1/ω) ≈ 2 at ω_max) the eigenvalue is then within ~2·tol, so
    the bound asserted is 3·tol. The start vector is fixed, so the result is also reproducible.
    """
    n = 3000
    stiffness = _chain_stiffness(n)
    jacobian = sp.bmat([[None, sp.identity(n)], [stiffness, None]], format="csr")
    omega_max = 2.0 * math.sin(n * math.pi / (2 * (n + 1)))
    dt = vv.analysis.max_stable_dt("velocity_verlet", jacobian=jacobian)
    tolerance = 3.0 * vv.analysis.stability.SPARSE_EIGEN_TOLERANCE
    assert dt == pytest.approx(2.0 / omega_max, rel=tolerance)
    assert vv.analysis.max_stable_dt("velocity_verlet", jacobian=jacobian) == dt


def test_state_jacobian_of_a_second_order_problem_with_mass():
    """[[0, I], [M⁻¹∂F/∂q, M⁻¹∂F/∂v]] for a damped spring pair with masses 1 and 4 kg."""
    stiffness = np.array([[-3.0, 1.0], [1.0, -2.0]])
    damping = np.array([[-0.1, 0.0], [0.0, -0.2]])
    masses = np.array([1.0, 4.0])
    problem = vv.ode.SecondOrderProblem.from_force(
        lambda t, q, v: q @ stiffness.T + v @ damping.T,
        masses,
        q0=[0.1, 0.0],
        v0=[0.0, 0.0],
        jacobian=lambda t, q, v: (stiffness, damping),
    )

    jacobian = vv.analysis.state_jacobian(problem.system(), problem.initial_state())
    expected = np.block(
        [[np.zeros((2, 2)), np.eye(2)], [stiffness / masses[:, None], damping / masses[:, None]]]
    )
    np.testing.assert_allclose(jacobian, expected)
