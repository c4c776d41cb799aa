"""Cloth grids (Choi & Ko 2002): the spring families and masses of the topology, and the stiff
cloth of the issue: implicit Euler's energy never increases and the strain stays within 1 %,
while symplectic Euler at the same step blows up within 10 steps."""

import numpy as np
import pytest

import visviva as vv
from visviva.deformables import cloth_grid
from visviva.deformables.topology import BEND, SHEAR, STRETCH
from visviva.forces import Springs


def test_a_grid_has_its_three_spring_families_and_weighs_density_times_area():
    sheet = cloth_grid(
        np.zeros(3), np.array([2.0, 0, 0]), np.array([0, 0, 1.0]), (10, 6), 0.3, 100, 50, 5
    )
    counts = {f: int((sheet.family == f).sum()) for f in (STRETCH, SHEAR, BEND)}
    # Structural: 9·6 along + 10·5 across; shear: two per cell; bend: 8·6 + 10·4.
    assert counts == {STRETCH: 9 * 6 + 10 * 5, SHEAR: 2 * 9 * 5, BEND: 8 * 6 + 10 * 4}
    assert sheet.mass.sum() == pytest.approx(0.3 * 2.0 * 1.0)
    cell = 0.3 * (2.0 / 9) * (1.0 / 5)
    assert sheet.mass[0] == pytest.approx(cell / 4)  # a corner: a quarter cell
    assert sheet.mass[1] == pytest.approx(cell / 2)  # an edge: half of two cells
    assert sheet.mass[11] == pytest.approx(cell)  # inside: a quarter of four cells
    np.testing.assert_allclose(sheet.points[10 * 5 + 9], [2.0, 0.0, 1.0])  # index j·nu + i
    lengths = sheet.rest_length()
    np.testing.assert_allclose(lengths[sheet.family == BEND][:8], 2 * 2.0 / 9)


def _stiff_cloth(method: str) -> vv.Simulation:
    builder = vv.SceneBuilder(name="stiff cloth")
    builder.set_integration(method=method, dt=1 / 60, duration=2.0)
    builder.add_cloth(
        (10, 10), stiffness=1e3, bending=10.0, areal_density=0.1, pinned=[0, 9], name="sheet"
    )  # 1 m × 1 m, horizontal, held at two corners
    return vv.Simulation(builder.build())


def test_stiff_cloth_implicit_euler_loses_energy_and_barely_stretches():
    simulation = _stiff_cloth("backward_euler")
    (springs,) = [f for f in simulation.model.forces if isinstance(f, Springs)]
    structural = slice(0, 2 * 9 * 10)  # the stretch family comes first
    energy = [simulation.energy()]
    strain = 0.0
    for _ in range(120):
        simulation.step()
        energy.append(simulation.energy())
        x = simulation.raw_state["particle_position"]
        pairs, rest = springs.pairs[structural], springs.rest_length[structural]
        length = np.linalg.norm(x[pairs[:, 1]] - x[pairs[:, 0]], axis=1)
        strain = max(strain, float((length / rest - 1.0).max()))
    # Backward Euler dissipates: the energy (kinetic + springs + gravity) never increases.
    assert np.diff(energy).max() <= 1e-9 * abs(energy[0])
    # The fabric stretches by less than 1 % (its structural springs' elongation).
    assert 0.0 < strain <= 0.01
    assert simulation.raw_state["particle_position"][95, 1] < 0.5  # the free edge has fallen


def test_stiff_cloth_symplectic_euler_blows_up_within_ten_steps():
    # ω = √(k/m) ≈ √(1e3 / 1.2e-3) ≈ 900/s for an inside point: h ω ≈ 15 ≫ 2.
    simulation = _stiff_cloth("symplectic_euler")
    with pytest.raises(vv.SimulationDiverged) as blow_up:
        simulation.step(10)
    assert blow_up.value.step < 10


def test_the_advisor_predicts_the_largest_stable_step_from_the_stiffest_springs():
    """Before the first step, the stability advisor's dt for symplectic Euler (from the
    spectrum of M⁻¹ ∂F/∂x, dominated by the stiffest springs on the lightest points) splits
    stable from unstable: 10 % below it the cloth runs 3000 steps, 10 % above it blows up."""
    from visviva.analysis.advisor import largest_stable_step

    def cloth(dt: float) -> vv.Simulation:
        builder = vv.SceneBuilder(name="advised")
        builder.set_integration(method="symplectic_euler", dt=dt, duration=100.0)
        builder.add_cloth((10, 10), stiffness=1e3, bending=10.0, areal_density=0.1, pinned=[0, 9])
        return vv.Simulation(builder.build())

    probe = cloth(1 / 60)
    advised = largest_stable_step(probe.system, probe.integrator, probe.raw_state)
    assert 1e-4 < advised < 1e-2
    below = cloth(0.9 * advised)
    below.step(3000)
    assert np.abs(below.state["particle_velocity"]).max() < 10.0
    with pytest.raises(vv.SimulationDiverged):
        cloth(1.1 * advised).step(3000)


def test_pinned_corners_stay_bit_identical():
    simulation = _stiff_cloth("backward_euler")
    start = simulation.state["particle_position"][[0, 9]]
    simulation.step(30)
    np.testing.assert_array_equal(simulation.state["particle_position"][[0, 9]], start)


@pytest.mark.parametrize(
    ("cloth", "message"),
    [
        ({"along": (1.0, 0.0, 0.0), "across": (2.0, 0.0, 0.0)}, "the sheet has no area"),
        ({"pinned": [100]}, "pinned index 100 is not a point of this cloth"),
        ({"resolution": (1, 5)}, "resolution"),
        ({"stiffness": -1.0}, "stiffness"),
        ({"along": (1e200, 0.0, 0.0), "across": (0.0, 0.0, 1e200)}, "beyond what a float holds"),
    ],
)
def test_bad_cloth_is_refused_naming_the_field(cloth, message):
    arguments = {"resolution": (10, 10), "stiffness": 100.0} | cloth
    builder = vv.SceneBuilder(name="bad")
    with pytest.raises(vv.ModelError, match=message):
        builder.add_cloth(**arguments)
        builder.build()


def test_cloth_drapes_over_a_sphere_with_baraff_witkins_step():
    """A stiff cloth falls onto a sphere: one linearized backward Euler step per frame (with
    the springs' definite Jacobian) takes it to rest around the ball without a failure; no
    point ends inside the sphere, and most of the sheet touches it or hangs below its top."""
    builder = vv.SceneBuilder(name="drape")
    builder.set_integration(method="linearly_implicit_euler", dt=1 / 60, duration=3.0)
    builder.add_cloth(
        (24, 24),
        stiffness=2e3,
        shear=100.0,
        bending=0.05,
        areal_density=0.1,
        damping=0.05,
        origin=(-0.6, 1.2, -0.6),
        along=(1.2, 0.0, 0.0),
        across=(0.0, 0.0, 1.2),
        radius=0.01,
    )
    builder.add_collider("sphere", name="ball", center=(0, 0.6, 0), radius=0.35, friction=0.5)
    simulation = vv.Simulation(builder.build())
    simulation.run(until=3.0)
    x = simulation.state["particle_position"]
    gap = np.linalg.norm(x - [0.0, 0.6, 0.0], axis=1) - 0.35 - 0.01
    assert gap.min() > -1e-9  # nothing inside the ball
    assert simulation.contacts().counts()["resting"] > 200  # of 576 points
    assert x[:, 1].min() < 0.6  # the corners hang below the ball's equator
    assert x[:, 1].max() < 0.96  # nothing left above the ball's top
    assert simulation.system.counters.newton_iterations == 180  # one linear solve a step


@pytest.mark.parametrize("preconditioner", ["multigrid", "jacobi"])
def test_baraff_witkins_step_by_cg_is_the_direct_solves_step(preconditioner):
    """The linearized step (M − hD − h²K) Δv = h (F + hK v) solved by block CG to a relative
    residual of 1e-10 is the sparse LU's step to 1e-9 of the velocities after 10 steps of a
    falling, buckling cloth; one linear solve a step, and CG's iterations are counted."""

    def run(**options):
        builder = vv.SceneBuilder(name="bw")
        builder.set_integration(method="symplectic_euler", dt=1 / 60, duration=1.0)
        builder.add_cloth(
            (12, 12), stiffness=1e3, shear=100.0, bending=1.0, damping=0.01, areal_density=0.1,
            origin=(0.0, 1.0, 0.0), along=(1.0, 0.0, 0.0), across=(0.0, 0.0, 1.0),
            pinned=[0, 11],
        )  # fmt: skip
        method = vv.integrators.LinearlyImplicitEuler(**options)
        simulation = vv.Simulation(builder.build(), method=method)
        simulation.step(10)
        return simulation

    cg = run(preconditioner=preconditioner, cg_rtol=1e-10)
    direct = run(linear_solver="direct")
    v, expected = cg.state["particle_velocity"], direct.state["particle_velocity"]
    np.testing.assert_allclose(v, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    assert cg.system.counters.linear_solves == direct.system.counters.linear_solves == 10
    assert cg.system.counters.krylov_iterations >= 10
    assert direct.system.counters.krylov_iterations == 0
