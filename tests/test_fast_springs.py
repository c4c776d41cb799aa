"""Liu et al.'s fast mass-spring step: it converges to backward Euler, stays stable where
explicit methods blow up, and holds pinned points."""

import numpy as np
import pytest

import visviva as vv
from visviva.integrators import FastMassSprings, ProjectedNewton

H = 1.0 / 60.0


def _cloth(n, *, stiffness=1000.0, damping=0.0, duration=1.0):
    builder = vv.SceneBuilder(name=f"cloth {n}")
    builder.set_world(gravity=(0.0, -9.81, 0.0))
    builder.set_integration(method="fast_mass_springs", dt=H, duration=duration)
    builder.add_cloth(
        (n, n), stiffness=stiffness, shear=stiffness / 10, bending=1.0, damping=damping,
        areal_density=0.1,
        origin=(0.0, 1.0, 0.0), along=(1.0, 0.0, 0.0), across=(0.0, 0.0, 1.0),
        pinned=[0, n - 1],
    )  # fmt: skip
    return builder.build()


def test_many_iterations_give_the_backward_euler_step():
    """Local/global alternation converges to backward Euler's minimizer: with 2000
    iterations per step its positions after 5 steps match projected Newton's (solved to
    1e-10) to 1e-6 m on an undamped cloth (gravity, the only other force, is constant, so
    taking it from the start of the step is exact)."""
    model = _cloth(5, stiffness=100.0, duration=5 * H)
    liu = vv.Simulation(model, method=FastMassSprings(iterations=2000))
    newton = vv.Simulation(model, method=ProjectedNewton(rtol=1e-12, atol=1e-12, cg_rtol=1e-12))
    liu.step(5)
    newton.step(5)
    np.testing.assert_allclose(
        liu.state["particle_position"], newton.state["particle_position"], rtol=0, atol=1e-6
    )
    assert liu.system.counters.newton_iterations == 5 * 2000


def test_few_iterations_stay_stable_where_symplectic_euler_blows_up():
    """10 iterations a step on a 12 × 12 cloth of 1e4 N/m springs at h = 1/60 s: bounded and
    finite for 3 s, pinned corners bit-identical; symplectic Euler at the same step diverges
    within a few steps."""
    model = _cloth(12, stiffness=1e4, damping=0.01, duration=3.0)
    sim = vv.Simulation(model)
    start = sim.state["particle_position"][[0, 11]].copy()
    sim.run(until=3.0)
    x = sim.state["particle_position"]
    assert np.isfinite(x).all() and np.abs(x).max() < 3.0
    assert np.array_equal(x[[0, 11]], start)
    explicit = vv.Simulation(model, method="symplectic_euler")
    with pytest.raises(vv.SimulationDiverged):
        explicit.run(until=1.0)


def test_iterations_must_be_a_positive_whole_number():
    with pytest.raises(vv.ModelError, match="iterations"):
        FastMassSprings(iterations=0)


def test_systems_without_springs_take_backward_euler():
    spring = vv.ode.SecondOrderProblem(lambda t, q: -q, q0=[1.0], v0=[0.0])
    ours = vv.solve(spring, FastMassSprings(), dt=0.1, until=1.0)
    euler = vv.solve(spring, "backward_euler", dt=0.1, until=1.0)
    np.testing.assert_allclose(ours.q, euler.q, rtol=0, atol=1e-12)
