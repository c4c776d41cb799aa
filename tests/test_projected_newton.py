"""Backward Euler as an energy minimization (``projected_newton``) and its block CG solver.

The incremental potential's gradient is the backward Euler residual and its Hessian the Newton
matrix (both checked against finite differences); the method agrees with exact backward Euler
where they solve the same equation; a 30 × 30 cloth falling from horizontal — buckling
everywhere — stays bounded with projection and line search, and the same run without them is
the one that fails.
"""

import numpy as np
import pytest
import scipy.sparse as sp

import visviva as vv
from visviva.errors import ModelError, NewtonConvergenceError
from visviva.integrators import ProjectedNewton, projected_newton
from visviva.integrators.block_cg import block_cg
from visviva.integrators.bsr import block_product
from visviva.integrators.newton_solve import newton_blocks
from visviva.integrators.projected_newton import _Merit
from visviva.model.scene_system import initial_state, scene_system

H = 1.0 / 60.0


def _cloth(n, *, damping=0.01, bending=1.0, method="symplectic_euler", duration=2.0):
    builder = vv.SceneBuilder(name=f"cloth {n}")
    builder.set_world(gravity=(0.0, -9.81, 0.0))
    builder.set_integration(method=method, dt=H, duration=duration)
    builder.add_cloth(
        (n, n), stiffness=1000.0, shear=100.0, bending=bending, damping=damping, areal_density=0.1,
        origin=(0.0, 1.0, 0.0), along=(1.0, 0.0, 0.0), across=(0.0, 0.0, 1.0),
        pinned=[0, n - 1],
    )  # fmt: skip
    return builder.build()


def _random_spd_blocks(rows, rng):
    """A random symmetric positive definite matrix with a random 3×3 block pattern."""
    dense = sp.random(rows, rows, density=0.2, random_state=rng).toarray()
    pattern = (dense + dense.T + np.eye(rows)) != 0
    values = rng.normal(size=(3 * rows, 3 * rows)) * np.kron(pattern, np.ones((3, 3)))
    matrix = values @ values.T + 3 * rows * np.eye(3 * rows)
    matrix *= np.kron(pattern, np.ones((3, 3)))  # keep the pattern; stays diagonally dominant
    return sp.bsr_matrix(matrix, blocksize=(3, 3)), matrix


def test_block_product_and_cg_solve_a_block_system():
    rng = np.random.default_rng(1)
    bsr, dense = _random_spd_blocks(20, rng)
    assert np.all(np.linalg.eigvalsh(dense) > 0)
    x = rng.normal(size=(20, 3))
    out = np.empty_like(x)
    block_product(bsr.indptr, bsr.indices, bsr.data, x, out)
    np.testing.assert_allclose(out.ravel(), dense @ x.ravel(), rtol=1e-12, atol=1e-12)
    b = rng.normal(size=(20, 3))
    solution = np.zeros_like(b)
    iterations, converged, positive = block_cg(
        bsr.indptr, bsr.indices, bsr.data, b, solution, 1e-12, 500
    )
    assert converged and positive and 0 < iterations <= 60  # CG: at most n = 60 exactly
    exact = np.linalg.solve(dense, b.ravel())
    np.testing.assert_allclose(solution.ravel(), exact, rtol=0, atol=1e-9 * np.abs(exact).max())
    # A warm start at the solution costs nothing.
    again, converged, _ = block_cg(bsr.indptr, bsr.indices, bsr.data, b, solution, 1e-8, 500)
    assert converged and again == 0


def test_cg_reports_negative_curvature_instead_of_dividing_by_it():
    # [[I, 2I], [2I, I]] has eigenvalues 3 and −1; b = (1, 1, 1, −1, −1, −1) is a −1 mode
    # (the diagonal blocks are I: the preconditioner leaves it as it is).
    identity = np.eye(3)
    matrix = sp.bsr_matrix(np.block([[identity, 2 * identity], [2 * identity, identity]]))
    matrix = matrix.tobsr(blocksize=(3, 3))
    b = np.array([[1.0, 1.0, 1.0], [-1.0, -1.0, -1.0]])
    x = np.zeros((2, 3))
    _, converged, positive = block_cg(matrix.indptr, matrix.indices, matrix.data, b, x, 1e-10, 50)
    assert not positive and not converged and np.isfinite(x).all()


def _newton_problem(damping):
    """A small crumpled cloth: the system, a state, and the stage's base."""
    model = _cloth(5, damping=damping)
    system = scene_system(model)
    q, v = initial_state(model).parts
    rng = np.random.default_rng(7)
    q = q + rng.normal(scale=0.05, size=q.shape)  # stretched and compressed springs
    v = v + rng.normal(scale=0.3, size=v.shape)
    held = np.repeat(model.particle_pinned, 3)
    v[held] = 0.0
    return system, q, v, held


@pytest.mark.parametrize("damping", [0.0, 0.3])
def test_incremental_potential_gradient_is_the_backward_euler_residual(damping):
    """∇Φ(V) = g(V) = M (V − v) − h (F(q + hV, 0) + D V) with the dampers' D held: central
    differences of Φ along random directions match gᵀu to 1e-6 relative."""
    system, q, v, held = _newton_problem(damping)
    mass = system.mass.diagonal()
    _, damping_matrix = system.force_jacobian(0.0, q + H * v, v, form="symmetric")
    merit = _Merit(system, 0.0, q, v, mass, H, damping_matrix, system.potential)
    rng = np.random.default_rng(3)
    velocity = v + rng.normal(scale=0.2, size=v.shape)
    velocity[held] = 0.0
    force = system.force(0.0, q + H * velocity, np.zeros_like(v))
    if damping_matrix is not None:
        force = force + damping_matrix @ velocity
    residual = mass * (velocity - v) - H * force
    for _ in range(5):
        u = rng.normal(size=v.shape)
        u[held] = 0.0  # pinned particles feel no force: Φ's gradient there is not g's
        e = 1e-6
        slope = (merit.value(velocity + e * u)[0] - merit.value(velocity - e * u)[0]) / (2 * e)
        assert slope == pytest.approx(float(residual @ u), rel=1e-6, abs=1e-12)


def test_newton_matrix_is_the_residuals_jacobian():
    """A = M − h D − h² K (symmetric form) against central differences of the residual."""
    system, q, v, held = _newton_problem(0.3)
    mass = system.mass.diagonal()
    stiffness, damping = system.force_jacobian(0.0, q + H * v, v, form="symmetric")
    blocks = np.empty_like(stiffness.data)
    newton_blocks(
        stiffness.indptr, stiffness.indices, stiffness.data, damping.data,
        mass.reshape(-1, 3), H, blocks,
    )  # fmt: skip
    newton = sp.bsr_matrix((blocks, stiffness.indices, stiffness.indptr), stiffness.shape)

    def residual(velocity):
        force = system.force(0.0, q + H * velocity, np.zeros_like(v)) + damping @ velocity
        return mass * (velocity - v) - H * force

    free = np.flatnonzero(~held)
    rng = np.random.default_rng(5)
    for _ in range(5):
        u = np.zeros_like(v)
        u[free] = rng.normal(size=free.shape)
        e = 1e-6
        numeric = (residual(v + e * u) - residual(v - e * u)) / (2 * e)
        np.testing.assert_allclose((newton @ u)[free], numeric[free], rtol=1e-6, atol=1e-9)
    assert abs(newton - newton.T).max() < 1e-12  # symmetric: CG applies


def test_agrees_with_exact_backward_euler_on_an_undamped_cloth():
    """Without dampers both solve M (V − v) = h F(q + hV) — the same equation; with tight
    tolerances the trajectories agree to 1e-8 m after 20 steps."""
    model = _cloth(6, damping=0.0, duration=20 * H)
    tight = ProjectedNewton(rtol=1e-12, atol=1e-12, cg_rtol=1e-12)
    ours = vv.Simulation(model, method=tight)
    exact = vv.Simulation(model, method="backward_euler")
    ours.step(20)
    exact.step(20)
    np.testing.assert_allclose(
        ours.state["particle_position"], exact.state["particle_position"], rtol=0, atol=1e-8
    )
    counters = ours.system.counters
    assert counters.newton_iterations >= 20 and counters.krylov_iterations > 0
    assert counters.linear_solves >= counters.newton_iterations


def _strain(model, positions):
    network = next(e for e in model.forces if isinstance(e, vv.forces.Springs))
    i, j = network.pairs.T
    length = np.linalg.norm(positions[j] - positions[i], axis=1)
    return np.abs(length / network.rest_length - 1.0)


def test_buckling_cloth_stays_bounded_with_projection_and_line_search():
    """A 30 × 30 cloth (k = 1000 N/m, 6 g points) falls from horizontal, pinned at two corners,
    for 2 s at h = 1/60 s: it buckles everywhere. With projection and line search every step
    converges, the energy never grows (backward Euler with dampers only dissipates, to the
    solver's tolerance) and springs stretch at most 10 %; pinned corners stay bit-identical."""
    model = _cloth(30)
    sim = vv.Simulation(model, method=ProjectedNewton())
    start = sim.state["particle_position"][[0, 29]].copy()
    energies = [sim.energy()]
    for _ in range(120):
        sim.step(1)
        energies.append(sim.energy())
    positions = sim.state["particle_position"]
    assert np.isfinite(positions).all()
    assert np.array_equal(positions[[0, 29]], start)
    growth = np.diff(energies)
    assert growth.max() <= 1e-6 * abs(energies[0]) + 1e-6  # [J]
    assert _strain(model, positions).max() < 0.10
    assert positions[:, 1].min() > -0.6  # hangs about a metre below the pins, no further


def test_the_same_cloth_without_projection_and_line_search_fails(monkeypatch):
    """Plain Newton — the exact (indefinite) Newton matrix, solved exactly, with full steps —
    does not converge on the same cloth within the first second, and says so rather than
    returning a wrong state. (Allowed to split failed steps, it gets through, with 65 steps
    split and 3.5× the projected run's Newton iterations; with block-Jacobi CG it fails even
    so: CG's early stop at negative curvature is a projection of its own.)"""
    monkeypatch.setattr(projected_newton, "SPLITS", 0)
    model = _cloth(30)
    method = ProjectedNewton(projection="never", line_search=False, linear_solver="direct")
    sim = vv.Simulation(model, method=method)
    with pytest.raises(NewtonConvergenceError, match="did not converge"):
        sim.step(60)


def test_options_are_checked():
    with pytest.raises(ModelError, match="projection"):
        ProjectedNewton(projection="sometimes")
    with pytest.raises(ModelError, match="linear_solver"):
        ProjectedNewton(linear_solver="magic")
    with pytest.raises(ModelError, match="cg_rtol"):
        ProjectedNewton(cg_rtol=0.0)


def test_direct_and_cg_solvers_take_the_same_steps():
    model = _cloth(8, duration=10 * H)
    runs = []
    for solver in ("cg", "direct"):
        sim = vv.Simulation(model, method=ProjectedNewton(linear_solver=solver, cg_rtol=1e-10))
        sim.step(10)
        runs.append(sim.state["particle_position"].copy())
    np.testing.assert_allclose(runs[0], runs[1], rtol=0, atol=1e-6)


def test_scene_files_name_the_method():
    model = _cloth(6, method="projected_newton", duration=5 * H)
    sim = vv.Simulation(model)
    sim.step(5)
    assert sim.system.counters.newton_iterations >= 5


def test_lagged_friction_gradient_and_hessian_match_finite_differences():
    """The friction potential μJ f₀(|T V|): its gradient and Hessian blocks against central
    differences, sliding faster and slower than the smoothing speed ε."""
    from visviva.integrators.friction import LaggedFriction

    rng = np.random.default_rng(11)
    normals = rng.normal(size=(6, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    normals[5] = 0.0  # a free point feels nothing
    friction = LaggedFriction(normals, rng.uniform(0.1, 1.0, 6), slip=1e-2)
    for scale in (1.0, 3e-3):  # above and below ε
        v = rng.normal(scale=scale, size=18)
        e = 1e-7 * scale
        numeric = np.array(
            [
                (friction.potential(v + e * u) - friction.potential(v - e * u)) / (2 * e)
                for u in np.eye(18)
            ]
        )
        np.testing.assert_allclose(friction.gradient(v).ravel(), numeric, rtol=1e-6, atol=1e-9)
        blocks = friction.blocks(v)
        for i in range(6):
            for a in range(3):
                u = np.zeros(18)
                u[3 * i + a] = e
                column = (friction.gradient(v + u) - friction.gradient(v - u))[i] / (2 * e)
                np.testing.assert_allclose(blocks[i, :, a], column, rtol=1e-5, atol=1e-6)
        assert np.all(np.linalg.eigvalsh(blocks) > -1e-12)  # convex: CG applies
    assert not blocks[5].any() and not friction.gradient(v)[5].any()


def _sliding_particle(friction):
    builder = vv.SceneBuilder(name="slide")
    builder.set_world(gravity=(0.0, -9.81, 0.0))
    builder.set_integration(method="projected_newton", dt=H, duration=1.0)
    builder.add_particles(
        positions=[[0.0, 0.05, 0.0]], velocities=[[2.0, 0.0, 0.0]], mass=0.1, radius=0.05
    )
    builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0), friction=friction)
    return vv.Simulation(builder.build())


def test_friction_inside_the_step_stops_a_sliding_particle_where_coulomb_says():
    """A particle sliding at v₀ = 2 m/s on a floor with μ = 0.5 decelerates at μg and stops
    after v₀²/(2μg) = 0.4077 m; backward Euler's positions lag by at most h v₀ = 3.3 cm. The
    floor holds it inside the solve: it never sinks, and the collision stage has nothing left
    to do (the energy only falls)."""
    sim = _sliding_particle(0.5)
    energies = []
    for _ in range(40):
        sim.step(1)
        energies.append(sim.energy())
    x, v = sim.state["particle_position"][0], sim.state["particle_velocity"][0]
    stop = 2.0**2 / (2 * 0.5 * 9.81)
    assert abs(x[0] - stop) <= H * 2.0
    assert abs(v[0]) < 1e-9  # static friction holds it once stopped
    assert x[1] >= 0.05 - 1e-12
    assert np.diff(energies).max() <= 1e-9
    # Without friction it keeps its speed.
    frictionless = _sliding_particle(0.0)
    frictionless.step(40)
    assert frictionless.state["particle_velocity"][0][0] == pytest.approx(2.0, rel=1e-9)


def test_cloth_drapes_over_a_sphere_held_inside_the_solve():
    """A stiff cloth falls onto a ball (impulse collider, μ = 0.5): projected Newton holds the
    touching points on the surface inside the solve, so no point ends inside, the solve's
    energy never grows, and the cloth stays on the ball."""
    builder = vv.SceneBuilder(name="drape")
    builder.set_integration(method="projected_newton", dt=H, duration=1.5)
    builder.add_cloth(
        (16, 16), stiffness=2e3, shear=100.0, bending=0.05, areal_density=0.1, damping=0.05,
        origin=(-0.6, 1.2, -0.6), along=(1.2, 0.0, 0.0), across=(0.0, 0.0, 1.2), radius=0.01,
    )  # fmt: skip
    builder.add_collider("sphere", name="ball", center=(0, 0.6, 0), radius=0.35, friction=0.5)
    sim = vv.Simulation(builder.build())
    sim.run(until=1.5)
    x = sim.state["particle_position"]
    gap = np.linalg.norm(x - [0.0, 0.6, 0.0], axis=1) - 0.35 - 0.01
    assert gap.min() > -1e-6  # nothing inside the ball
    assert x[:, 1].max() < 0.96  # nothing left above the ball's top
    assert x[:, 1].min() > 0.0  # still on the ball, hanging around it
    assert np.isfinite(x).all()


def _bob(method, omega_h):
    """A 1 kg bob hanging by a spring (k = 100 N/m, ω = 10 rad/s) from a pinned point,
    released where the spring is unstretched: a linear oscillator along the spring, of
    amplitude mg/k, stepped at ``ω h``."""
    builder = vv.SceneBuilder(name="bob")
    builder.set_world(gravity=(0.0, -9.81, 0.0))
    h = omega_h / 10.0
    builder.set_integration(method="symplectic_euler", dt=h, duration=200 * h)
    builder.add_rope([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]], mass=1.0, stiffness=100.0, pinned=[0])
    return vv.Simulation(builder.build(), method=method)


@pytest.mark.parametrize("omega_h", [0.5, 2.0])
def test_projected_trapezoidal_keeps_a_linear_oscillators_energy(omega_h):
    """On a linear oscillator the trapezoidal rule's |R(iωh)| = 1: the oscillation's energy
    E − E_eq = ½ k (mg/k)² stays to round-off for 200 steps even at ωh = 2, far beyond
    explicit stability, while backward Euler's shrinks by 1/(1 + (ωh)²) per step."""
    tight = {"rtol": 1e-12, "atol": 1e-14, "cg_rtol": 1e-14}
    trapezoid = _bob(vv.integrators.ProjectedTrapezoidal(**tight), omega_h)
    euler = _bob(vv.integrators.ProjectedNewton(**tight), omega_h)
    sag = 9.81 / 100.0
    equilibrium = 0.5 * 100.0 * sag**2 - 9.81 * (1.0 + sag)  # E_eq [J]
    oscillation = 0.5 * 100.0 * sag**2  # [J]
    assert trapezoid.energy() - equilibrium == pytest.approx(oscillation, rel=1e-12)
    trapezoid.step(200)
    euler.step(200)
    assert trapezoid.energy() - equilibrium == pytest.approx(oscillation, rel=1e-9)
    assert euler.energy() - equilibrium < oscillation * (1.0 / (1.0 + omega_h**2)) ** 100


@pytest.mark.parametrize(
    ("method", "order"), [(ProjectedNewton, 1), (vv.integrators.ProjectedTrapezoidal, 2)]
)
def test_measured_order_on_a_scene(method, order):
    """The bob on a spring against its closed form y(t) = y_eq + (y₀ − y_eq) cos ωt: halving
    h divides the error at t = 1 s by 2^order (within 15 %)."""
    tight = {"rtol": 1e-12, "atol": 1e-14, "cg_rtol": 1e-14}
    sag = 9.81 / 100.0
    exact = -1.0 - sag + sag * np.cos(10.0 * 1.0)  # y₀ − y_eq = sag
    errors = []
    for omega_h in (0.04, 0.02, 0.01):
        sim = _bob(method(**tight), omega_h)
        sim.step(round(1.0 / (omega_h / 10.0)))
        errors.append(abs(sim.state["particle_position"][1, 1] - exact))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    np.testing.assert_allclose(ratios, 2.0**order, rtol=0.15)
