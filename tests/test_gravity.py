"""Gravitation against closed forms, conservation laws, a NumPy reference and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

import visviva as vv
from visviva.errors import ModelError
from visviva.mechanics import barnes_hut, octree
from visviva.mechanics.gravity import PointMasses

mech = vv.mechanics
EPS = np.finfo(np.float64).eps


def numpy_accelerations(x, m, G, softening):
    """The reference: a_i = G Σ_{j≠i} m_j (x_j − x_i) / (|x_j − x_i|² + ε²)^{3/2}."""
    d = x[None, :, :] - x[:, None, :]
    r2 = (d**2).sum(axis=-1) + softening**2
    np.fill_diagonal(r2, np.inf)
    return G * (m[None, :, None] * d / r2[..., None] ** 1.5).sum(axis=1)


def random_bodies(n, seed=0):
    rng = np.random.default_rng(seed)
    return rng.standard_normal((n, 3)), rng.uniform(0.1, 2.0, n)


# --- direct summation ------------------------------------------------------------------------


@pytest.mark.parametrize("softening", [0.0, 0.05])
def test_accelerations_match_the_numpy_formula(softening):
    x, m = random_bodies(60)
    m[7] = 0.0  # a test particle: pulled, pulls nothing
    expected = numpy_accelerations(x, m, 2.5, softening)
    got = mech.gravity_accelerations(x, m, G=2.5, softening=softening)
    # Each entry is a sum of 59 terms of either sign: rounding ~ N ε relative to the largest.
    np.testing.assert_allclose(got, expected, rtol=0, atol=60 * EPS * np.abs(expected).max())
    assert np.abs(got[7]).max() > 0.0


def test_si_default_gives_the_surface_gravity_of_the_earth():
    """G M / R² with CODATA G, M = 5.9722e24 kg, R = 6.371e6 m: 9.8199 m/s²."""
    a = mech.gravity_accelerations([[0, 0, 0], [0, 6.371e6, 0]], [5.9722e24, 70.0])
    assert a[1, 1] == pytest.approx(-6.6743e-11 * 5.9722e24 / 6.371e6**2, rel=1e-14)


def test_pair_forces_are_bitwise_antisymmetric():
    """Equal masses: a_0 = −a_1 exactly, for any positions and scales (momentum by construction:
    m_i m_j and r² are symmetric, x_j − x_i is antisymmetric in floating point)."""
    rng = np.random.default_rng(4)
    for _ in range(300):
        x = rng.standard_normal((2, 3)) * 10.0 ** rng.uniform(-5, 5)
        m = np.full(2, 10.0 ** rng.uniform(-20, 40))
        a = mech.gravity_accelerations(x, m, G=1.0, softening=rng.choice([0.0, 1e-3]))
        np.testing.assert_array_equal(a[0], -a[1])


def test_total_force_vanishes_to_round_off():
    """Σ m_i a_i is a sum of exactly cancelling pairs, rounded once per addition: a few ε of
    Σ |m_i a_i|, whatever the mass ratios."""
    x, m = random_bodies(2000, seed=1)
    m *= 10.0 ** np.random.default_rng(2).uniform(-6, 6, m.size)
    force = m[:, None] * mech.gravity_accelerations(x, m, G=1.0, softening=0.01)
    assert np.abs(force.sum(axis=0)).max() <= 8 * EPS * np.abs(force).sum()


@pytest.mark.parametrize("softening", [0.0, 0.1])
def test_acceleration_is_minus_the_gradient_of_the_potential_over_mass(softening):
    """Central differences of U with step h: truncation ~h² U''' and rounding ~ε U/h; with
    h = 1e-5 both are below 1e-8 of |a| here."""
    x, m = random_bodies(12, seed=3)
    a = mech.gravity_accelerations(x, m, G=1.0, softening=softening)
    h = 1e-5
    gradient = np.empty_like(x)
    for body in range(len(m)):
        for axis in range(3):
            plus, minus = x.copy(), x.copy()
            plus[body, axis] += h
            minus[body, axis] -= h
            potential = [
                mech.gravitational_potential_energy(p, m, G=1.0, softening=softening)
                for p in (plus, minus)
            ]
            gradient[body, axis] = (potential[0] - potential[1]) / (2 * h)
    np.testing.assert_allclose(-gradient / m[:, None], a, atol=1e-8 * np.abs(a).max())


def test_potential_energy_of_three_bodies():
    """U = −G Σ_{i<j} m_i m_j / √(r² + ε²) by hand."""
    x = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 4.0, 0.0]])
    m = np.array([1.0, 2.0, 3.0])
    expected = -(2.0 / math.sqrt(9.25) + 3.0 / math.sqrt(16.25) + 6.0 / math.sqrt(25.25))
    got = mech.gravitational_potential_energy(x, m, G=1.0, softening=0.5)
    assert got == pytest.approx(expected, rel=1e-15)


def test_momentum_of_a_softened_cluster_is_conserved():
    """64 bodies, ε = 0.05, velocity Verlet: each kick adds h Σ m_i a_i, zero to round-off, and
    each drift leaves P alone, so P stays put to 1e-13 of Σ |m_i v_i| over 2000 steps."""
    cluster = mech.plummer_sphere(64, total_mass=1.0, scale_radius=1.0, G=1.0, seed=5)
    solution = vv.solve(
        cluster.problem(softening=0.05), "velocity_verlet", dt=2e-3, until=4.0, record_every=100
    )
    v = solution.v.reshape(len(solution.t), 64, 3)
    x = solution.q.reshape(len(solution.t), 64, 3)
    momentum = vv.analysis.linear_momentum(cluster.masses, v)
    scale = np.abs(cluster.masses[:, None] * v[0]).sum()
    np.testing.assert_allclose(momentum - momentum[0], 0.0, rtol=0, atol=1e-13 * scale)
    assert np.abs(x[-1] - x[0]).max() > 0.1  # the bodies did move
    # Each drift moves Σ m x by h P, so the centre of mass moves uniformly: Σ m x(t) = Σ m x0 +
    # P t, to the rounding of 2000 drifts of bodies a few units from the origin.
    centre = cluster.masses @ x
    expected = centre[0] + solution.t[:, None] * momentum[0]
    np.testing.assert_allclose(centre, expected, rtol=0, atol=1e-12)


# --- Kepler -------------------------------------------------------------------------------


def test_eccentric_anomaly_solves_keplers_equation():
    mean = np.linspace(-20.0, 20.0, 401)
    for e in (0.0, 0.3, 0.9, 0.999):
        anomaly = mech.eccentric_anomaly(mean, e)
        np.testing.assert_allclose(anomaly - e * np.sin(anomaly), mean, rtol=0, atol=1e-13)


def test_kepler_orbit_has_its_closed_form_invariants():
    orbit = mech.kepler_orbit(2.0, 0.6, masses=(3.0, 1.0), G=1.0)
    for t in (0.0, 0.37 * orbit.period, 5.2):
        bodies = orbit.bodies(t)
        potential = mech.gravitational_potential_energy(bodies.positions, bodies.masses, G=1.0)
        assert bodies.kinetic_energy() + potential == pytest.approx(orbit.energy, rel=1e-13)
        angular = vv.analysis.angular_momentum(bodies.masses, bodies.positions, bodies.velocities)
        np.testing.assert_allclose(angular, [0.0, orbit.angular_momentum, 0.0], atol=1e-13)
        np.testing.assert_allclose(bodies.momentum(), 0.0, atol=1e-15)
    assert orbit.period == pytest.approx(2 * math.pi * math.sqrt(8.0 / 4.0), rel=1e-15)


KEPLER = mech.kepler_orbit(1.0, 0.5, masses=(1.0, 1e-3), G=1.0)


@pytest.mark.parametrize("method", ["velocity_verlet", "leapfrog"])
def test_kepler_energy_and_angular_momentum_over_a_thousand_orbits(method):
    """e = 0.5, 1000 steps per orbit, 1000 orbits (the issue's bounds): a symplectic method
    keeps |ΔE/E| bounded near (n h)² times a pericentre factor, ~1e-4, with no drift; and
    conserves L exactly for a central force, so only rounding remains (~1e-13)."""
    dt = KEPLER.period / 1000
    solution = vv.solve(
        KEPLER.bodies().problem(), method, dt=dt, until=1000 * KEPLER.period, record_every=101
    )
    energy = solution.energy
    assert np.abs(energy - energy[0]).max() / abs(energy[0]) <= 2e-4
    frames = len(solution.t)
    x, v = solution.q.reshape(frames, 2, 3), solution.v.reshape(frames, 2, 3)
    angular = vv.analysis.angular_momentum(np.array(KEPLER.masses), x, v)
    assert np.abs(angular - angular[0]).max() / np.linalg.norm(angular[0]) <= 1e-11
    assert solution.counters["accepted_steps"] == 1_000_000


def test_kepler_positions_follow_the_ellipse_with_second_order_error():
    """Over 10 orbits velocity Verlet's error is a phase lag growing like C (n h)² t/T a; halving
    h divides it by 4 (order 2). C ≈ 45 for e = 0.5 (the fast pericentre passage dominates):
    the bound allows 60."""
    errors = []
    for steps in (1000, 2000):
        solution = vv.solve(
            KEPLER.bodies().problem(),
            "velocity_verlet",
            dt=KEPLER.period / steps,
            until=10 * KEPLER.period,
            record_every=steps // 10,
        )
        exact = KEPLER.positions(solution.t).reshape(len(solution.t), 6)
        errors.append(np.abs(solution.q - exact).max())
        bound = 60 * (2 * math.pi / steps) ** 2 * 10 * KEPLER.semi_major_axis
        assert errors[-1] <= bound
    assert 3.6 <= errors[0] / errors[1] <= 4.4


# --- Barnes–Hut ---------------------------------------------------------------------------


def test_barnes_hut_within_its_documented_error():
    cluster = mech.plummer_sphere(20_000, total_mass=1.0, scale_radius=1.0, G=1.0, seed=6)
    args = (cluster.positions, cluster.masses)
    exact = mech.gravity_accelerations(*args, G=1.0, softening=0.01)
    for theta, (median, p99) in barnes_hut.ERROR_BOUNDS.items():
        tree = mech.gravity_accelerations(
            *args, G=1.0, softening=0.01, method="barnes_hut", theta=theta
        )
        error = np.linalg.norm(tree - exact, axis=1) / np.linalg.norm(exact, axis=1)
        assert np.median(error) <= median, theta
        assert np.percentile(error, 99) <= p99, theta


def test_tree_force_error_measures_against_direct_summation():
    """All bodies compared: the same figures as comparing the two methods by hand; a sample of
    them: close to those figures (the median of 1500 draws is within a few percent)."""
    cluster = mech.plummer_sphere(3000, total_mass=1.0, scale_radius=1.0, G=1.0, seed=16)
    args = (cluster.positions, cluster.masses)
    options = {"G": 1.0, "softening": 0.01, "theta": 0.7}
    exact = mech.gravity_accelerations(*args, G=1.0, softening=0.01)
    tree = mech.gravity_accelerations(*args, method="barnes_hut", **options)
    by_hand = np.linalg.norm(tree - exact, axis=1) / np.linalg.norm(exact, axis=1)
    everything = mech.tree_force_error(*args, sample=10**6, **options)
    assert everything.compared == 3000 and everything.theta == 0.7
    assert everything.median == pytest.approx(np.median(by_hand), rel=1e-9)
    assert everything.p99 == pytest.approx(np.percentile(by_hand, 99), rel=1e-9)
    assert everything.largest == pytest.approx(by_hand.max(), rel=1e-9)
    sampled = mech.tree_force_error(*args, sample=1500, seed=2, **options)
    assert sampled.compared == 1500
    assert sampled.median == pytest.approx(everything.median, rel=0.1)
    with pytest.raises(ModelError, match=r"`sample` must be at least 1"):
        mech.tree_force_error(*args, sample=0)
    with pytest.raises(ModelError, match=r"no compared body feels any force"):
        mech.tree_force_error([[0.0, 0.0, 0.0]], [1.0])


def test_barnes_hut_potential_energy_is_close_to_direct():
    cluster = mech.plummer_sphere(5000, total_mass=1.0, scale_radius=1.0, G=1.0, seed=7)
    args = (cluster.positions, cluster.masses)
    exact = mech.gravitational_potential_energy(*args, G=1.0, softening=0.01)
    tree = mech.gravitational_potential_energy(
        *args, G=1.0, softening=0.01, method="barnes_hut", theta=0.5
    )
    assert tree == pytest.approx(exact, rel=1e-4)


@pytest.mark.parametrize("softening", [0.0, 0.05])
def test_barnes_hut_is_direct_summation_for_a_single_group(softening):
    x, m = random_bodies(barnes_hut.GROUP_SIZE, seed=8)
    expected = numpy_accelerations(x, m, 1.0, softening)
    got = mech.gravity_accelerations(x, m, G=1.0, softening=softening, method="barnes_hut")
    np.testing.assert_allclose(got, expected, rtol=0, atol=200 * EPS * np.abs(expected).max())


def test_barnes_hut_degenerate_inputs():
    tree = {"G": 1.0, "method": "barnes_hut"}
    # One body: nothing pulls it.
    np.testing.assert_array_equal(mech.gravity_accelerations([[1.0, 2.0, 3.0]], [5.0], **tree), 0)
    # Two bodies: exact.
    two = mech.gravity_accelerations([[0, 0, 0], [2, 0, 0]], [1.0, 3.0], **tree)
    np.testing.assert_allclose(two, [[0.75, 0, 0], [-0.25, 0, 0]], rtol=1e-15)
    # A million bodies at one point with softening: no force, potential −G m (M − m)/ε each,
    # and no O(N²) loop (this would take hours).
    n = 1_000_000
    point = np.tile([1.0, -2.0, 0.5], (n, 1))
    masses = np.full(n, 1.0 / n)
    np.testing.assert_array_equal(
        mech.gravity_accelerations(point, masses, softening=0.1, **tree), 0.0
    )
    energy = mech.gravitational_potential_energy(point, masses, softening=0.1, **tree)
    assert energy == pytest.approx(-0.5 * (1.0 - 1.0 / n) / 0.1, rel=1e-9)


def test_barnes_hut_with_a_huge_coordinate_range():
    """A cluster of 300 bodies 1e-6 m across and two bodies 1e60 m away: the cells shrink to
    their bodies, so the tree stays shallow and the forces match direct summation."""
    x, m = random_bodies(300, seed=9)
    x = np.vstack([1e-6 * x, [[1e60, 0, 0], [0, -1e60, 1e60]]])
    m = np.append(m, [1.0, 2.0])
    bodies = PointMasses(x, m, 0.0)
    assert octree.build_octree(bodies).depth < 10
    exact = numpy_accelerations(x, m, 1.0, 0.0)
    got = mech.gravity_accelerations(x, m, G=1.0, method="barnes_hut", theta=0.5)
    error = np.linalg.norm(got - exact, axis=1) / np.linalg.norm(exact, axis=1)
    assert np.median(error) <= barnes_hut.ERROR_BOUNDS[0.5][0]


def test_barnes_hut_with_masses_beyond_single_precision():
    """Masses over 45 decades, so that some cells are lighter (relative to the heaviest body)
    than float32 can hold: forces stay within the documented error."""
    x, _ = random_bodies(2000, seed=17)
    m = 10.0 ** np.random.default_rng(18).uniform(-45.0, 0.0, 2000)
    exact = numpy_accelerations(x, m, 1.0, 0.01)
    got = mech.gravity_accelerations(x, m, G=1.0, softening=0.01, method="barnes_hut")
    error = np.linalg.norm(got - exact, axis=1) / np.linalg.norm(exact, axis=1)
    assert np.median(error) <= barnes_hut.ERROR_BOUNDS[0.5][0]
    assert np.percentile(error, 99) <= barnes_hut.ERROR_BOUNDS[0.5][1]


def test_octree_keeps_every_body_once_and_orders_cells():
    x, m = random_bodies(5000, seed=10)
    tree = octree.build_octree(PointMasses(x, m, 0.0))
    np.testing.assert_array_equal(np.sort(tree.order), np.arange(5000))
    np.testing.assert_array_equal(tree.x, x[tree.order, 0])
    leaves = tree.first_child < 0
    assert tree.size[leaves].sum() == 5000
    assert tree.size[leaves].max() <= octree.LEAF_SIZE
    internal = np.flatnonzero(~leaves)
    assert (tree.first_child[internal] > internal).all()  # children after their parent
    assert (tree.children[internal] >= 2).all()


# --- initial conditions ---------------------------------------------------------------------


def test_plummer_sphere_is_in_virial_equilibrium():
    """K/|U| = ½ in expectation; the sampling scatter of the ratio is ≈ 0.32/√N (measured over
    seeds), so 4σ at N = 4096 is 0.02."""
    cluster = mech.plummer_sphere(4096, total_mass=2.0, scale_radius=0.5, G=1.0, seed=11)
    potential = mech.gravitational_potential_energy(cluster.positions, cluster.masses, G=1.0)
    assert cluster.kinetic_energy() / abs(potential) == pytest.approx(0.5, abs=0.02)
    assert np.abs(cluster.momentum()).max() <= 1e-15
    np.testing.assert_allclose(cluster.masses @ cluster.positions, 0.0, atol=1e-14)
    # Half the mass within 1.305 a (here a = 0.5), to sampling precision.
    half = np.median(np.linalg.norm(cluster.positions, axis=1))
    assert half == pytest.approx(1.305 * 0.5, rel=0.05)


def test_initial_conditions_are_reproducible_from_a_seed():
    first = mech.plummer_sphere(100, total_mass=1.0, scale_radius=1.0, seed=3)
    again = mech.plummer_sphere(100, total_mass=1.0, scale_radius=1.0, seed=3)
    other = mech.plummer_sphere(100, total_mass=1.0, scale_radius=1.0, seed=4)
    np.testing.assert_array_equal(first.positions, again.positions)
    np.testing.assert_array_equal(first.velocities, again.velocities)
    assert not np.array_equal(first.positions, other.positions)


def test_disk_galaxy_bodies_circle_the_centre():
    """Massless disk, no softening: every disk body moves at √(G M / r) perpendicular to its
    radius, in the plane normal to `normal`, counter-clockwise about it."""
    normal = np.array([1.0, 2.0, 2.0]) / 3.0
    galaxy = mech.disk_galaxy(
        500, central_mass=4.0, disk_mass=0.0, radius=2.0, G=1.0, normal=normal, seed=12
    )
    r = galaxy.positions[1:] - galaxy.positions[0]
    v = galaxy.velocities[1:] - galaxy.velocities[0]
    distance = np.linalg.norm(r, axis=1)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), np.sqrt(4.0 / distance), rtol=1e-14)
    np.testing.assert_allclose(r @ normal, 0.0, atol=1e-14)
    np.testing.assert_allclose((r * v).sum(axis=1), 0.0, atol=1e-13)
    assert (np.cross(r, v) @ normal > 0).all()
    assert distance.min() >= 0.2 - 1e-12 and distance.max() <= 2.0


def test_colliding_disks_start_on_a_parabola():
    """The centres' relative orbit has zero energy and the angular momentum √(2 μ q) of a
    parabola with pericenter q; total momentum is zero."""
    bodies = mech.colliding_disks(
        50, central_mass=1.0, disk_mass=0.5, radius=1.0, separation=10.0, pericenter=2.0, G=1.0
    )
    assert bodies.count == 102
    galaxies = [slice(0, 51), slice(51, 102)]
    mass = [bodies.masses[g].sum() for g in galaxies]
    x = [bodies.masses[g] @ bodies.positions[g] / mass[k] for k, g in enumerate(galaxies)]
    v = [bodies.masses[g] @ bodies.velocities[g] / mass[k] for k, g in enumerate(galaxies)]
    mu = sum(mass)  # G = 1
    r, w = x[1] - x[0], v[1] - v[0]
    assert np.linalg.norm(r) == pytest.approx(10.0, rel=1e-14)
    assert 0.5 * w @ w - mu / np.linalg.norm(r) == pytest.approx(0.0, abs=1e-14)
    assert np.linalg.norm(np.cross(r, w)) == pytest.approx(math.sqrt(2 * mu * 2.0), rel=1e-13)
    np.testing.assert_allclose(bodies.momentum(), 0.0, atol=1e-14)


def test_sun_earth_moon_year_and_month():
    """Two years with velocity Verlet, h = 1 h. The Earth's sidereal year is 365.256 d; the
    run gives 365.254 d (its Kepler period plus the Moon's tug), asserted to ±0.05 d. The
    Moon's sidereal month is 27.32 d; the truncated lunar theory that places the Moon gives
    27.28 d (its starting velocity is ~0.1% off), asserted to 27.3 ± 0.1 d."""
    system = mech.sun_earth_moon()
    np.testing.assert_allclose(system.momentum(), 0.0, atol=1e-16 * 2e30 * 3e4)
    day = 86_400.0
    solution = vv.solve(system.problem(), "velocity_verlet", dt=3600.0, until=730.5 * day)
    x = solution.q.reshape(len(solution.t), 3, 3)

    def mean_period(relative):
        # Longitude in the ecliptic (x–z plane), counter-clockwise seen from +y.
        angle = np.unwrap(np.arctan2(-relative[:, 2], relative[:, 0]))
        turns = (angle - angle[0]) / (2 * math.pi)
        whole = math.floor(turns[-1])
        return np.interp(whole, turns, solution.t) / whole / day

    assert mean_period(x[:, 1] - x[:, 0]) == pytest.approx(365.256, abs=0.05)
    assert mean_period(x[:, 2] - x[:, 1]) == pytest.approx(27.3, abs=0.1)


# --- problems -------------------------------------------------------------------------------


def test_batched_problem_matches_separate_runs():
    """Two 12-body systems in one batch (kernel path) give the same frames as each alone."""
    clusters = [
        mech.plummer_sphere(12, total_mass=1.0, scale_radius=1.0, G=1.0, seed=s) for s in (1, 2)
    ]
    masses = clusters[0].masses
    batch = mech.nbody_problem(
        np.stack([c.positions for c in clusters]),
        np.stack([c.velocities for c in clusters]),
        masses,
        G=1.0,
        softening=0.05,
    )
    together = vv.solve(batch, "leapfrog", dt=1e-2, until=1.0, record_every=20)
    for k, cluster in enumerate(clusters):
        alone = vv.solve(cluster.problem(softening=0.05), "leapfrog", dt=1e-2, until=1.0)
        np.testing.assert_allclose(together.q[-1, k], alone.q[-1], rtol=0, atol=1e-12)
        assert together.energy[-1, k] == pytest.approx(alone.energy[-1], rel=1e-12)


def test_compiled_few_body_path_matches_the_kernels():
    """Three bodies take the compiled one-system acceleration; Barnes–Hut (one group, so exact)
    takes the parallel kernels: the same trajectory to rounding."""
    bodies = mech.plummer_sphere(3, total_mass=1.0, scale_radius=1.0, G=1.0, seed=13)
    compiled = vv.solve(bodies.problem(softening=0.1), "velocity_verlet", dt=1e-2, until=2.0)
    kernel = vv.solve(
        bodies.problem(softening=0.1, method="barnes_hut"), "velocity_verlet", dt=1e-2, until=2.0
    )
    np.testing.assert_allclose(compiled.q, kernel.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(compiled.energy, kernel.energy, rtol=1e-12)


# --- bad input ------------------------------------------------------------------------------

TWO = ([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [1.0, 1.0])


@pytest.mark.parametrize(
    ("positions", "masses", "kwargs", "message"),
    [
        (*TWO[:1], [1.0, -2.0], {}, r"`masses` of body 1 must be finite and zero or positive"),
        (*TWO[:1], [1.0, math.nan], {}, r"`masses` of body 1"),
        ([[0, 0, 0], [1, math.inf, 0]], TWO[1], {}, r"`positions` of body 1 must be finite"),
        ([[0, 0, 0], [1e101, 0, 0]], TWO[1], {}, r"within ±1e\+100 m"),
        ([[0, 0], [1, 0]], TWO[1], {}, r"shape \(N, 3\) \(got shape \(2, 2\)\)"),
        (*TWO[:1], [1.0, 1.0, 1.0], {}, r"`masses` must have shape \(2,\), one per body"),
        (np.zeros((0, 3)), [], {}, r"at least one body"),
        (*TWO, {"theta": 0.0}, r"`theta` must be positive"),
        (*TWO, {"theta": 1.5}, r"`theta` must be in \(0, 1\]"),
        (*TWO, {"method": "barnes-hut"}, r"unknown `method` 'barnes-hut'.*'barnes_hut'\?"),
        (*TWO, {"method": "tree"}, r"unknown `method` 'tree'; choose 'direct' or 'barnes_hut'"),
        (*TWO, {"softening": -1.0}, r"`softening` must be zero or positive"),
        (*TWO, {"G": 0.0}, r"`G` must be positive"),
        (*TWO, {"out": np.empty((3, 3))}, r"`out` must be a float64 array of shape \(2, 3\)"),
    ],
)
def test_bad_input_is_refused_with_the_field_named(positions, masses, kwargs, message):
    with pytest.raises(ModelError, match=message):
        mech.gravity_accelerations(positions, masses, **kwargs)


@pytest.mark.parametrize("method", ["direct", "barnes_hut"])
def test_coincident_bodies_without_softening_are_refused(method):
    x, m = random_bodies(10, seed=14)
    x[7] = x[3]
    with pytest.raises(ModelError, match=r"bodies 3 and 7 coincide at .*; give `softening` > 0"):
        mech.gravity_accelerations(x, m, method=method)
    with pytest.raises(ModelError, match=r"bodies 3 and 7 coincide"):
        mech.gravitational_potential_energy(x, m, method=method)
    with pytest.raises(ModelError, match=r"bodies 3 and 7 coincide"):
        mech.nbody_problem(x, np.zeros_like(x), m, method=method)
    # With softening they are fine: coincident bodies pull each other with zero force.
    assert np.isfinite(mech.gravity_accelerations(x, m, softening=0.1, method=method)).all()


def test_bad_problems_and_initial_conditions_are_refused():
    x, v, m = np.zeros((2, 3)), np.zeros((2, 3)), np.ones(2)
    x[1, 0] = 1.0
    with pytest.raises(ModelError, match=r"`velocities` must have the shape of `positions`"):
        mech.nbody_problem(x, np.zeros((3, 3)), m)
    with pytest.raises(ModelError, match=r"`positions` must have shape \(N, 3\), or \(batch"):
        mech.nbody_problem(x.ravel(), v.ravel(), m)
    with pytest.raises(ModelError, match=r"`eccentricity` must be below 1"):
        mech.kepler_orbit(1.0, 1.0, masses=(1.0, 1.0))
    with pytest.raises(ModelError, match=r"`masses\[1\]` must be positive"):
        mech.kepler_orbit(1.0, 0.5, masses=(1.0, 0.0))
    with pytest.raises(ModelError, match=r"`separation` .* must be at least `pericenter`"):
        mech.colliding_disks(
            5, central_mass=1, disk_mass=0, radius=1, separation=1.0, pericenter=2.0
        )
    with pytest.raises(ModelError, match=r"`n` must be at least 1"):
        mech.plummer_sphere(0, total_mass=1.0, scale_radius=1.0)
    with pytest.raises(ModelError, match=r"`normal` must be a finite, non-zero 3-vector"):
        mech.disk_galaxy(5, central_mass=1, disk_mass=0, radius=1, normal=(0, 0, 0))
    with pytest.raises(ModelError, match=r"`names` must name all 2 bodies"):
        mech.Bodies(x, v, m, names=("one",))
