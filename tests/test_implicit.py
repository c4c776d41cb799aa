"""Implicit methods: Newton with analytic or finite-difference Jacobians, dense or sparse,
any mass matrix — and every analytic Jacobian shipped with visviva checked against finite
differences of the same function."""

import numpy as np
import pytest
import scipy.sparse as sp

import visviva as vv
from visviva.analysis.reference_problems import reference_problem, reference_problems
from visviva.ode.system import _finite_difference

IMPLICIT = [m for m in vv.integrators.names() if vv.integrators.get(m).implicit]


def _without_jacobian(problem):
    """The same problem with its Jacobian removed (so Newton uses finite differences)."""
    energy = None if problem.energy is None else problem.energy.func
    if problem.kind == "first_order":
        return vv.ode.FirstOrderProblem(problem.f.func, problem.y0, problem.t0, energy=energy)
    return vv.ode.SecondOrderProblem(
        problem.force.func, problem.q0, problem.v0, problem.t0, energy=energy
    )


@pytest.mark.parametrize("method", IMPLICIT)
@pytest.mark.parametrize("name", ["pendulum", "damped", "first-order"])
def test_finite_difference_newton_agrees_with_analytic(method, name):
    """Same answer to the Newton tolerance whether the Jacobian is analytic or by differences;
    finite differences cost extra evaluations of f, the analytic one none."""
    problem = reference_problem(name).problem
    analytic = vv.solve(problem, method, dt=0.05, until=3.0)
    numeric = vv.solve(_without_jacobian(problem), method, dt=0.05, until=3.0)
    for field in analytic.recording.fields:
        np.testing.assert_allclose(
            numeric.recording[field], analytic.recording[field], rtol=0, atol=1e-9
        )
    assert numeric.counters["f_evaluations"] > analytic.counters["f_evaluations"]
    assert analytic.counters["newton_iterations"] == analytic.counters["linear_solves"]


@pytest.mark.parametrize(
    "name", [n for n in reference_problems() if reference_problem(n).problem.jacobian is not None]
)
def test_reference_jacobians_match_finite_differences(name):
    """Every analytic Jacobian shipped with a reference problem equals differences of its f."""
    problem = reference_problem(name).problem
    system = problem.system()
    state = problem.initial_state()
    rng = np.random.default_rng(5)
    for _ in range(3):
        parts = tuple(p + rng.normal(scale=0.3, size=p.shape) for p in state.parts)
        t = float(rng.uniform(0, 3))
        if problem.kind == "first_order":
            (y,) = parts
            analytic = system.jacobian(t, y)
            numeric = _finite_difference(lambda x: system.rhs(t, x), y, system.rhs(t, y))
            np.testing.assert_allclose(analytic, numeric, rtol=1e-6, atol=1e-6)
        else:
            q, v = parts
            force = system.force(t, q, v)
            stiffness, damping = system.force_jacobian(t, q, v)
            np.testing.assert_allclose(
                stiffness,
                _finite_difference(lambda x: system.force(t, x, v), q, force),
                rtol=1e-6,
                atol=1e-6,
            )
            if damping is not None:
                np.testing.assert_allclose(
                    damping,
                    _finite_difference(lambda x: system.force(t, q, x), v, force),
                    rtol=1e-6,
                    atol=1e-6,
                )


def test_demo_jacobians_match_finite_differences():
    """The demos' hand-written Jacobians are those of their accelerations."""
    from visviva.demos.circular import circular_problem
    from visviva.demos.oscillator import oscillator_problem

    for problem in (oscillator_problem(), circular_problem()):
        system = problem.system()
        q = np.array([0.37])
        numeric = _finite_difference(lambda x: system.force(0.0, x, x), q, system.force(0.0, q, q))
        np.testing.assert_allclose(system.force_jacobian(0.0, q, q)[0], numeric, rtol=1e-6)


def _chain(n, k=50.0, damping=0.3):
    """n unit masses on a line, joined by springs k and dashpots, both ends fixed:
    F = K q + D v with tridiagonal K = k·(−2, 1, 1), D = −damping·I."""
    stiffness = sp.diags(
        [np.full(n - 1, k), np.full(n, -2 * k), np.full(n - 1, k)], [-1, 0, 1], format="csr"
    )

    def force(t, q, v):
        return stiffness @ q - damping * v

    def jacobian(t, q, v):
        return stiffness, -damping * sp.identity(n, format="csr")

    q0 = np.sin(np.linspace(0, np.pi, n + 2)[1:-1])
    return force, jacobian, q0, stiffness


@pytest.mark.parametrize("method", IMPLICIT)
def test_sparse_newton_matches_dense(method):
    """A 200-mass chain with a scipy.sparse Jacobian (SuperLU) gives the dense result."""
    force, jacobian, q0, _ = _chain(200)

    def dense_jacobian(t, q, v):
        k, d = jacobian(t, q, v)
        return k.toarray(), d.toarray()

    sparse = vv.ode.SecondOrderProblem(force, q0, np.zeros_like(q0), jacobian=jacobian)
    dense = vv.ode.SecondOrderProblem(force, q0, np.zeros_like(q0), jacobian=dense_jacobian)
    a = vv.solve(sparse, method, dt=0.05, until=1.0)
    b = vv.solve(dense, method, dt=0.05, until=1.0)
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-10)


def test_backward_euler_is_exact_for_the_linear_chain_recurrence():
    """For M q'' = K q + D v, backward Euler is (M − hD − h²K) v' = M v + h K q: one linear
    solve per step, which Newton must reproduce to round-off."""
    n, h = 30, 0.1
    force, jacobian, q0, stiffness = _chain(n)
    problem = vv.ode.SecondOrderProblem(force, q0, np.zeros(n), jacobian=jacobian)
    solution = vv.solve(problem, "backward_euler", dt=h, until=2.0)
    k = stiffness.toarray()
    d = -0.3 * np.eye(n)
    q, v = q0.copy(), np.zeros(n)
    for _ in range(20):
        v = np.linalg.solve(np.eye(n) - h * d - h * h * k, v + h * k @ q)
        q = q + h * v
    np.testing.assert_allclose(solution.q[-1], q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(solution.v[-1], v, rtol=0, atol=1e-12)


@pytest.mark.parametrize("form", ["diagonal", "dense", "sparse"])
@pytest.mark.parametrize(
    "method", ["backward_euler", "implicit_midpoint", "rk4", "velocity_verlet"]
)
def test_mass_matrix_forms_agree(form, method):
    """M q'' = F with M given as a diagonal, a dense or a sparse matrix: the same motion as
    the acceleration M⁻¹F (here M = diag(1, 2, 3) kg on a chain of three springs)."""
    masses = np.array([1.0, 2.0, 3.0])
    force, jacobian, q0, _ = _chain(3, k=5.0)
    mass = {"diagonal": masses, "dense": np.diag(masses), "sparse": sp.diags(masses)}[form]
    with_mass = vv.ode.SecondOrderProblem.from_force(
        force, mass, q0, np.zeros(3), jacobian=jacobian
    )
    scaled = vv.ode.SecondOrderProblem(lambda t, q, v: force(t, q, v) / masses, q0, np.zeros(3))
    a = vv.solve(with_mass, method, dt=0.01, until=1.0)
    b = vv.solve(scaled, method, dt=0.01, until=1.0)
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-9)


def test_batched_newton_equals_separate_solves():
    """One Newton iteration over a batch solves each system's own (n × n) matrix."""
    problem = reference_problem("pendulum").problem
    angles = np.array([[0.3], [1.0], [2.5], [3.0]])
    batch = vv.ode.SecondOrderProblem(
        problem.force.func, angles, np.zeros_like(angles), jacobian=problem.jacobian.func
    )
    together = vv.solve(batch, "trapezoidal", dt=0.1, until=5.0)
    for i, angle in enumerate(angles):
        alone = vv.solve(
            vv.ode.SecondOrderProblem(
                problem.force.func, angle, [0.0], jacobian=problem.jacobian.func
            ),
            "trapezoidal",
            dt=0.1,
            until=5.0,
        )
        np.testing.assert_allclose(together.q[:, i], alone.q, rtol=0, atol=1e-10)


def test_stiff_decay_is_handled_by_backward_euler_not_explicit():
    """Seed 000 on stiffness: λ = −1e4 with dt = 0.01 (hλ = −100). Explicit Euler diverges and
    says why; backward Euler decays like the exact solution."""
    problem = vv.ode.FirstOrderProblem(
        lambda t, y: -1e4 * (y - np.cos(t)), [2.0], jacobian=lambda t, y: np.full((1, 1), -1e4)
    )
    assert not vv.solve(problem, "explicit_euler", dt=0.01, until=10.0).success
    implicit = vv.solve(problem, "backward_euler", dt=0.01, until=10.0)
    # After the transient, y follows cos t to O(1/|λ|) plus the O(h) method error.
    np.testing.assert_allclose(implicit.y[50:, 0], np.cos(implicit.t[50:]), atol=2e-3)


def test_line_search_rescues_newton_where_full_steps_diverge(monkeypatch):
    """A block braking under smoothed Coulomb friction, F = −(2/π) μ m g atan(v/ε): with a
    large step, full Newton steps on backward Euler's equation v − v_n + h μ g (2/π) atan(v/ε)
    = 0 overshoot like Newton on atan and diverge; backtracking on the residual's norm
    converges to the root, which the test checks against bisection."""
    mu_g, eps, h, v0 = 300.0, 0.01, 0.5, 3.0  # h μ g (2/π) ≈ 95: the root is near 3e-4 m/s

    def force(t, q, v):
        return -mu_g * (2 / np.pi) * np.arctan(v / eps)

    def jacobian(t, q, v):
        return np.zeros((1, 1)), np.array([[-mu_g * (2 / np.pi) / (eps * (1 + (v[0] / eps) ** 2))]])

    problem = vv.ode.SecondOrderProblem(force, [0.0], [v0], jacobian=jacobian)
    solution = vv.solve(problem, "backward_euler", dt=h, until=h)
    assert solution.success and solution.recording.attrs["line_search_steps"] > 0

    def residual(v):
        return v - v0 - h * force(0.0, 0.0, v)

    low, high = -v0, v0
    for _ in range(200):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if residual(middle) < 0 else (low, middle)
    np.testing.assert_allclose(solution.v[-1, 0], 0.5 * (low + high), rtol=1e-9)
    # Without it, the full steps fly off and the step fails (with a clear error).
    monkeypatch.setattr("visviva.integrators.newton.LINE_SEARCH_HALVINGS", 0)
    assert not vv.solve(problem, "backward_euler", dt=h, until=h).success
