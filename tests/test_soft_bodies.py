"""Soft lattices (seed 004's volumetric soft bodies): the springs and masses of the lattice, and a
jelly cube dropped on a floor that lands, keeps its shape and comes to rest on its face."""

import numpy as np
import pytest

import visviva as vv
from visviva.deformables import soft_lattice
from visviva.deformables.topology import DIAGONAL, SHEAR, STRETCH


def test_a_lattice_has_its_three_families_and_weighs_density_times_volume():
    lattice = soft_lattice(np.zeros(3), np.array([1.0, 2.0, 3.0]), (3, 4, 5), 100.0, 10, 5, 2)
    counts = {f: int((lattice.family == f).sum()) for f in (STRETCH, SHEAR, DIAGONAL)}
    # Structural: 2·4·5 + 3·3·5 + 3·4·4; two diagonals on each cell face (2·3·5 + 2·4·4 +
    # 3·4·3 faces); four through each of the 2·3·4 cells.
    assert counts == {STRETCH: 133, SHEAR: 2 * (30 + 32 + 36), DIAGONAL: 4 * 24}
    assert lattice.mass.sum() == pytest.approx(100.0 * 6.0)
    cell = 100.0 * (0.5 * (2 / 3) * 0.75)
    assert lattice.mass[0] == pytest.approx(cell / 8)  # a corner touches one cell
    np.testing.assert_allclose(lattice.points[-1], [1.0, 2.0, 3.0])  # (k·ny + j)·nx + i
    lengths = lattice.rest_length()
    np.testing.assert_allclose(lengths[lattice.family == DIAGONAL], np.sqrt(0.25 + 4 / 9 + 0.5625))


@pytest.mark.parametrize(
    ("method", "dt"), [("symplectic_euler", 5e-4), ("linearly_implicit_euler", 1e-2)]
)
def test_a_jelly_cube_lands_on_the_floor_and_keeps_its_shape(method, dt):
    builder = vv.SceneBuilder(name="jelly")
    builder.set_integration(method=method, dt=dt, duration=2.0)
    builder.add_soft_lattice(
        (6, 6, 6),
        stiffness=2000.0,
        density=200.0,
        damping=0.5,
        origin=(-0.15, 0.5, -0.15),
        size=(0.3, 0.3, 0.3),
        radius=0.01,
    )
    builder.add_collider("plane", name="floor", friction=0.6, restitution=0.2)
    simulation = vv.Simulation(builder.build())
    simulation.run(until=2.0)
    x = simulation.state["particle_position"]
    extent = x.max(axis=0) - x.min(axis=0)
    # On the floor (the lowest points rest at their radius), not crushed and not splayed.
    assert x[:, 1].min() == pytest.approx(0.01, abs=1e-9)
    assert np.prod(extent) == pytest.approx(0.3**3, rel=0.05)
    # Its weight (5.4 kg on 36 bottom points) sags it by millimetres, not centimetres.
    assert x[:, 1].mean() == pytest.approx(0.01 + 0.15, abs=0.01)
    assert simulation.contacts().counts()["resting"] >= 30
