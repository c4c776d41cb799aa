"""The stencil of a lattice's springs sums the same forces as the springs one by one.

Each point's force from its springs, f_p = Σ_q (k (l − L) + c (v_q − v_p)·u) u with
u = (x_q − x_p)/l (seed 002), is computed by the stencil from both ends of every spring and by
:class:`Springs` once per spring and gathered: the two agree to round-off on cloth grids and
soft lattices of every small shape (edges and corners included), with
springs stretched, compressed and moving. Springs that are not exactly a lattice's (one
missing, a stiffness of their own, an end outside) keep the general path.
"""

import numpy as np
import pytest

import visviva as vv
from visviva.deformables.topology import cloth_grid, soft_lattice
from visviva.forces.lattice_springs import SpringStencil
from visviva.forces.springs import Springs


def _forces(springs: Springs, x: np.ndarray, v: np.ndarray) -> np.ndarray:
    out = np.zeros_like(x)
    springs.accumulate(0.0, x, v, out)
    return out


def _both(network, start=0, extra=0, seed=0, damping=0.3):
    """The network's springs as a stencil and one by one, in a scene of ``start`` particles
    before it and ``extra`` after, and a perturbed, moving configuration."""
    rng = np.random.default_rng(seed)
    n = network.points.shape[0]
    count = start + n + extra
    # Rest lengths 0.8–1.2 of the built ones: springs start stretched and compressed.
    rest = network.rest_length() * rng.uniform(0.8, 1.2, network.pairs.shape[0])
    pairs = network.pairs + start
    args = (pairs, rest, network.stiffness, damping, count)
    stencil = Springs(*args, lattice=(network.lattice, start))
    general = Springs(*args)
    x = rng.normal(0.0, 1.0, (count, 3))
    x[start : start + n] = network.points + rng.normal(0.0, 0.02, (n, 3))
    v = rng.normal(0.0, 1.0, (count, 3))
    return stencil, general, x, v


@pytest.mark.parametrize("resolution", [(2, 2), (3, 2), (2, 5), (3, 3), (7, 4), (5, 9), (16, 16)])
def test_cloth_stencil_sums_the_springs_forces(resolution):
    network = cloth_grid(
        np.zeros(3), np.array([1.0, 0.0, 0.2]), np.array([0.0, 0.1, 1.0]), resolution,
        0.1, 1000.0, 100.0, 2.0,
    )  # fmt: skip
    stencil, general, x, v = _both(network, start=3, extra=2)
    assert stencil.stencil is not None and general.stencil is None
    expected = _forces(general, x, v)
    got = _forces(stencil, x, v)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    # Particles outside the lattice feel nothing from it.
    assert not got[:3].any() and not got[-2:].any()


@pytest.mark.parametrize("resolution", [(2, 2, 2), (3, 2, 2), (2, 3, 4), (4, 3, 5), (2, 2, 6)])
def test_soft_lattice_stencil_sums_the_springs_forces(resolution):
    network = soft_lattice(
        np.zeros(3), np.array([1.0, 0.7, 1.3]), resolution, 1000.0, 500.0, 200.0, 100.0
    )
    stencil, general, x, v = _both(network, start=1, seed=1)
    assert stencil.stencil is not None
    # 3 structural, 6 face and 4 body diagonals: those with room in the lattice.
    assert stencil.stencil.offsets.shape[0] <= 13
    expected = _forces(general, x, v)
    np.testing.assert_allclose(
        _forces(stencil, x, v), expected, rtol=0, atol=1e-12 * np.abs(expected).max()
    )


def test_the_two_ends_of_a_spring_feel_opposite_forces():
    """One spring along each offset alone: the stencil's two computations of it (once from
    each end) give +f and −f to round-off, so the forces sum to zero."""
    network = cloth_grid(
        np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), (6, 5),
        0.1, 1000.0, 100.0, 2.0,
    )  # fmt: skip
    stencil, _, x, v = _both(network)
    force = _forces(stencil, x, v)
    scale = np.abs(force).max()
    np.testing.assert_allclose(force.sum(axis=0), 0.0, atol=1e-13 * scale * force.shape[0])


def _grid():
    return cloth_grid(
        np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), (5, 4),
        0.1, 1000.0, 100.0, 2.0,
    )  # fmt: skip


def test_springs_that_are_not_exactly_a_lattices_keep_the_general_path():
    network = _grid()
    pairs, rest, k = network.pairs, network.rest_length(), network.stiffness
    shape = network.lattice
    assert SpringStencil.of(pairs, rest, k, np.zeros_like(k), shape, 0) is not None
    # A spring missing from its offset's family.
    assert SpringStencil.of(pairs[1:], rest[1:], k[1:], np.zeros_like(k[1:]), shape, 0) is None
    # One spring with a stiffness, or a damping, of its own.
    own = k.copy()
    own[7] *= 2.0
    assert SpringStencil.of(pairs, rest, own, np.zeros_like(k), shape, 0) is None
    damping = np.zeros_like(k)
    damping[3] = 0.1
    assert SpringStencil.of(pairs, rest, k, damping, shape, 0) is None
    # An end beyond the lattice (the lattice said to start one particle later).
    assert SpringStencil.of(pairs, rest, k, np.zeros_like(k), shape, 1) is None
    # A spring repeated in place of another of its family.
    twice = pairs.copy()
    twice[1] = twice[0]
    assert SpringStencil.of(twice, rest, k, np.zeros_like(k), shape, 0) is None
    # Such springs still sum correctly, one by one.
    springs = Springs(pairs, rest, own, 0.1, 20, lattice=(shape, 0))
    assert springs.stencil is None


def test_scene_bodies_on_lattices_take_the_stencil_and_agree_with_the_general_step():
    """A rope (no lattice), a cloth and a jelly block in one scene: the lattices' springs are
    stencils, the rope's are not, and the fused step gives the generic pipeline's result
    (which sums the same stencils through Springs.accumulate) to round-off."""
    builder = vv.SceneBuilder(name="lattices")
    builder.set_integration(method="symplectic_euler", dt=2e-4, duration=1.0)
    builder.add_rope(
        [[x, 1.5, 0.0] for x in np.linspace(0.0, 0.5, 6)], mass=0.01, stiffness=200.0,
        pinned=[0],
    )  # fmt: skip
    builder.add_cloth(
        (9, 7), stiffness=500.0, shear=50.0, bending=1.0, damping=0.01, areal_density=0.1,
        origin=(-0.5, 0.8, -0.5), along=(1.0, 0.0, 0.0), across=(0.0, 0.0, 1.0), pinned=[0, 8],
    )  # fmt: skip
    builder.add_soft_lattice(
        (3, 4, 3), origin=(1.0, 0.3, 0.0), size=(0.2, 0.3, 0.2), stiffness=800.0, damping=0.05
    )
    builder.add_collider("plane", restitution=0.0, friction=0.5)
    model = builder.build()
    springs = [f for f in model.forces if isinstance(f, Springs)]
    assert [s.stencil is not None for s in springs] == [False, True, True]
    fused, generic = vv.Simulation(model), vv.Simulation(model, compiled=False)
    assert fused.compiled and not generic.compiled
    fused.step(300)
    generic.step(300)
    for name in ("particle_position", "particle_velocity"):
        np.testing.assert_allclose(
            fused.raw_state[name], generic.raw_state[name], rtol=0, atol=1e-9, err_msg=name
        )
