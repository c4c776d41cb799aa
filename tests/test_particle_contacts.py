"""Particle–particle collisions (spheres): closed forms of 1-D impacts, Coulomb's bound,
momentum to round-off, resting stacks and piles, contacts, bad input, hostile input."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import visviva as vv
from visviva.collision.contact_classes import COLLIDING, RESTING, SEPARATING
from visviva.collision.particle_contacts import ParticleContacts
from visviva.errors import ModelError, SceneError
from visviva.ode.workspace import Workspace

H = 1e-3  # [s]


def collide(mass, x, v, radius, *, e=0.5, mu=0.0, x0=None, alive=None, iterations=10, **kw):
    """One stage pass (no gravity) over copies of ``x``, ``v``; returns them and the contacts
    solved."""
    mass = np.asarray(mass, dtype=float)
    x, v = np.array(x, dtype=float), np.array(v, dtype=float)
    stage = ParticleContacts(
        1.0 / mass, restitution=e, friction=mu, iterations=iterations, gravity=(0, 0, 0), **kw
    )
    alive = np.ones(len(mass), dtype=bool) if alive is None else np.asarray(alive)
    start = x.copy() if x0 is None else np.asarray(x0, dtype=float)
    work = Workspace()
    radii = np.broadcast_to(np.asarray(radius, float), mass.shape)
    stage.resolve(start, x, v, radii, alive, H, work=work)
    return x, v, stage.solved(work)


@pytest.mark.parametrize("e", [0.0, 0.25, 0.5, 0.9, 1.0])
def test_head_on_equal_spheres_conserve_momentum_and_scale_the_approach_by_e(e):
    """Newton's law of restitution along the line of centres: v_rel' = −e v_rel; total momentum
    unchanged to round-off (1e-14 relative)."""
    x = [[-0.099, 0.2, 0.3], [0.099, 0.2, 0.3]]  # overlapping by 2 mm, centres along x
    v = [[1.5, 0.0, 0.0], [-0.5, 0.0, 0.0]]
    mass = [0.2, 0.2]
    x1, v1, _ = collide(mass, x, v, 0.1, e=e)
    p0, p1 = (np.array(mass)[:, None] * v).sum(0), (np.array(mass)[:, None] * v1).sum(0)
    assert np.abs(p1 - p0).max() <= 1e-14 * np.abs(p0).max()
    assert v1[0, 0] - v1[1, 0] == pytest.approx(-e * 2.0, rel=1e-14, abs=1e-15)
    assert np.abs(v1[:, 1:]).max() == 0.0
    assert np.linalg.norm(x1[0] - x1[1]) == pytest.approx(0.2, rel=1e-14)  # overlap removed
    assert (x1[0] + x1[1]) / 2 == pytest.approx((np.array(x[0]) + x[1]) / 2, abs=1e-16)


@pytest.mark.parametrize(("m1", "m2", "e"), [(1.0, 3.7, 0.6), (5.0, 0.25, 1.0), (2.0, 2e3, 0.3)])
def test_unequal_masses_follow_the_closed_form_of_a_1d_collision(m1, m2, e):
    """v₁' = ((m₁ − e m₂) v₁ + (1 + e) m₂ v₂)/(m₁ + m₂) and the same with 1 ↔ 2."""
    v1, v2 = 2.0, -0.75
    x, v, _ = collide(
        [m1, m2], [[0.0, 0.0, -0.05], [0.0, 0.0, 0.049]], [[0, 0, v1], [0, 0, v2]], [0.05, 0.0495],
        e=e,
    )  # fmt: skip
    expected1 = ((m1 - e * m2) * v1 + (1 + e) * m2 * v2) / (m1 + m2)
    expected2 = ((m2 - e * m1) * v2 + (1 + e) * m1 * v1) / (m1 + m2)
    assert v[0, 2] == pytest.approx(expected1, rel=1e-13, abs=1e-14)
    assert v[1, 2] == pytest.approx(expected2, rel=1e-13, abs=1e-14)
    # The overlap is removed in the ratio of the inverse masses: the centre of mass stays.
    centre = (m1 * x[0, 2] + m2 * x[1, 2]) / (m1 + m2)
    assert centre == pytest.approx((m1 * -0.05 + m2 * 0.049) / (m1 + m2), abs=1e-16)


@pytest.mark.parametrize("mu", [0.05, 0.3, 10.0])
def test_oblique_impact_friction_is_bounded_by_mu_times_the_normal_impulse(mu):
    """Coulomb: |J_t| ≤ μ J_n; at equality while the spheres still slide, and a sliding that
    stops is not reversed (the tangential relative velocity ends at 0, not beyond)."""
    mass = np.array([1.0, 2.0])
    n = np.array([np.cos(0.4), np.sin(0.4), 0.0])  # from sphere 1 towards sphere 0
    t = np.array([-np.sin(0.4), np.cos(0.4), 0.0])
    x = [0.199 * n, [0.0, 0.0, 0.0]]
    v = [-1.0 * n + 2.0 * t, [0.0, 0.0, 0.0]]
    _, v1, _ = collide(mass, x, v, 0.1, e=0.4, mu=mu)
    impulse = mass[0] * (v1[0] - np.array(v[0]))  # on sphere 0
    normal, tangential = impulse @ n, impulse @ t
    assert normal == pytest.approx((1 + 0.4) * 1.0 * (2.0 / 3.0), rel=1e-13)  # (1 + e) m* |v_n|
    assert abs(tangential) <= mu * normal * (1 + 1e-13)
    sliding_after = (v1[0] - v1[1]) @ t
    if mu * normal < 2.0 * 2.0 / 3.0:  # not enough to stop the slide: Coulomb's bound holds
        assert abs(tangential) == pytest.approx(mu * normal, rel=1e-13)
        assert sliding_after > 0.0
    else:
        assert sliding_after == pytest.approx(0.0, abs=1e-14)


def test_spheres_that_pass_through_each_other_within_a_step_are_caught():
    """A chord through the other sphere: the normal is the one at the first touch."""
    x0 = [[-0.3, 0.0, 0.0], [0.3, 0.0, 0.0]]
    x = [[0.25, 0.0, 0.0], [-0.25, 0.0, 0.0]]  # swapped sides within the step (0.55 m each)
    v = [[550.0, 0.0, 0.0], [-550.0, 0.0, 0.0]]
    x1, v1, _ = collide([1.0, 1.0], x, v, 0.1, e=1.0, x0=x0)
    assert v1[0, 0] == pytest.approx(-550.0, rel=1e-14)
    assert x1[1, 0] - x1[0, 0] == pytest.approx(0.2, rel=1e-12)  # back on their own sides


def test_dead_slots_never_collide():
    x = [[0.0, 0.0, 0.0], [0.05, 0.0, 0.0], [0.1, 0.0, 0.0]]
    v = [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]
    x1, v1, last = collide([1.0, 1.0, 1.0], x, v, 0.1, alive=[True, False, True])
    np.testing.assert_array_equal(x1[1], x[1])
    np.testing.assert_array_equal(v1[1], v[1])
    pairs = {tuple(sorted((a, b))) for a, b in zip(last.first, last.second, strict=True)}
    assert pairs == {(0, 2)}


def scene_column(count: int, iterations: int = 20) -> vv.SceneBuilder:
    r = 0.02
    builder = vv.SceneBuilder(name="column")
    builder.set_integration(method="symplectic_euler", dt=2e-3, duration=1.5)
    points = [[0.0, 2 * r + k * 2.3 * r, 0.0] for k in range(count)]
    builder.add_particles(points, radius=r, mass=0.01, name="balls")
    builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0), restitution=0.3, friction=0.3)
    builder.add_particle_collisions(restitution=0.3, friction=0.3, iterations=iterations)
    return builder


def test_a_dropped_column_comes_to_rest_stacked():
    """Ten balls dropped on a floor end stacked at y_k = r + 2 r k, at rest, overlapping by
    less than 1 % of a radius (warm-started impulses converge over the steps)."""
    r = 0.02
    simulation = vv.Simulation(scene_column(10).build())
    simulation.run(until=1.5)
    y = simulation.state["particle_position"][:, 1]
    np.testing.assert_allclose(y, r + 2 * r * np.arange(10), atol=0.01 * r)
    assert np.abs(simulation.state["particle_velocity"]).max() < 0.05  # [m/s]: g·dt is 0.02
    contacts = simulation.pair_contacts()
    assert len(contacts) == 9 and contacts.depth.max() < 0.01 * r
    np.testing.assert_array_equal(contacts.second - contacts.first, 1)  # each on the one below
    assert set(contacts.classes()) == {"resting"}


def test_spheres_beyond_the_grids_reach_are_refused_at_build_and_stop_a_run_cleanly():
    """The grid bins cells of a diameter up to 2⁴⁰ of them from the origin: a sphere placed
    beyond is a scene error; one that flies beyond stops the run with an explanation."""
    builder = vv.SceneBuilder(name="far")
    builder.set_world(gravity=(0.0, 0.0, 0.0))
    builder.add_particles([[1e200, 1.0, 0.0], [0.0, 1.0, 0.0]], radius=0.05, name="balls")
    builder.add_particle_collisions()
    with pytest.raises(SceneError, match=r"entities\[1\].*beyond the grid's reach"):
        builder.build()
    builder = vv.SceneBuilder(name="fast")
    builder.set_world(gravity=(0.0, 0.0, 0.0))
    builder.set_integration(dt=0.01, duration=1.0)
    builder.add_particles(
        [[0.0, 1.0, 0.0], [1.0, 1.0, 0.0]], velocities=[[1e14, 0.0, 0.0], [0.0, 0.0, 0.0]],
        radius=0.05, name="balls",
    )  # fmt: skip
    builder.add_particle_collisions()
    simulation = vv.Simulation(builder.build())
    with pytest.raises(vv.SimulationError, match=r"particle collisions: .*beyond the grid's reach"):
        simulation.run(until=1.0)


def test_pair_contacts_of_a_scene_without_particle_collisions_say_how_to_add_them():
    builder = vv.SceneBuilder(name="apart")
    builder.add_particles([[0.0, 1.0, 0.0], [0.01, 1.0, 0.0]], radius=0.05)
    with pytest.raises(ModelError, match='add an entity of type "particle_collisions"'):
        vv.Simulation(builder.build()).pair_contacts()


def test_momentum_of_a_closed_cloud_is_conserved_to_round_off():
    """2000 spheres, no gravity, no walls, e = 0.8, μ = 0.3: 200 steps of collisions change
    the total momentum by round-off only."""
    rng = np.random.default_rng(5)
    builder = vv.SceneBuilder(name="gas")
    builder.set_world(gravity=(0.0, 0.0, 0.0))
    builder.set_integration(method="symplectic_euler", dt=H, duration=0.2)
    count = 2000
    builder.add_particles(
        rng.uniform(-0.5, 0.5, (count, 3)).tolist(),
        velocities=rng.normal(0.0, 1.0, (count, 3)).tolist(),
        mass=rng.uniform(0.5, 2.0, count).tolist(),
        radius=rng.uniform(0.02, 0.04, count).tolist(),
    )
    builder.add_particle_collisions(restitution=0.8, friction=0.3)
    model = builder.build()
    simulation = vv.Simulation(model)
    m = np.asarray(model.particle_mass)[:, None]
    p0 = (m * simulation.state["particle_velocity"]).sum(0)
    scale = (m * np.abs(simulation.state["particle_velocity"])).sum()
    simulation.run(until=0.2)
    p1 = (m * simulation.state["particle_velocity"]).sum(0)
    solved = model.stages[0].solved(simulation.system.workspace)
    assert solved.first.shape[0] > 100  # it did collide
    assert np.abs(p1 - p0).max() <= 1e-13 * scale
    x = simulation.state["particle_position"]
    assert (m * x).sum(0) / m.sum() == pytest.approx(
        (m * np.asarray(model.particle_position)).sum(0) / m.sum() + 0.2 * p0 / m.sum(), abs=1e-12
    )


def test_contacts_are_classified_colliding_resting_and_separating():
    """Baraff's classes by the relative normal velocity against the resting speed."""
    stage = ParticleContacts(np.ones(8), resting_speed=0.1, gravity=(0, 0, 0))
    x = np.array(
        [[0, 0, 0], [0.19, 0, 0], [5, 0, 0], [5, 0.2, 0], [9, 0, 0], [9, 0, 0.21], [20, 0, 0],
         [23, 0, 0]], dtype=float,
    )  # fmt: skip
    v = np.zeros((8, 3))
    v[1, 0] = -1.0  # colliding: approaching at 1 m/s
    v[3, 1] = -0.05  # resting: touching, approaching slower than the resting speed
    v[5, 2] = 0.5  # separating, and 1 cm apart: a contact only with a gap of 1 cm allowed
    state = {
        "particle_position": x,
        "particle_velocity": v,
        "particle_radius": np.full(8, 0.1),
        "particle_alive": np.ones(8, dtype=bool),
    }
    contacts = stage.pair_contacts(state)
    assert contacts.first.tolist() == [0, 2] and contacts.second.tolist() == [1, 3]
    assert contacts.kind.tolist() == [COLLIDING, RESTING]
    np.testing.assert_allclose(contacts.normal, [[-1, 0, 0], [0, -1, 0]])
    np.testing.assert_allclose(contacts.depth, [0.01, 0.0], atol=1e-15)
    np.testing.assert_allclose(contacts.normal_velocity, [-1.0, -0.05])
    np.testing.assert_allclose(contacts.point, [[0.095, 0, 0], [5, 0.1, 0]], atol=1e-15)
    wide = stage.pair_contacts(state, gap=0.02)
    assert wide.classes() == ["colliding", "resting", "separating"]
    assert wide.counts() == {"colliding": 1, "resting": 1, "separating": 1}
    assert wide.kind[2] == SEPARATING and wide.depth[2] == pytest.approx(-0.01)


@pytest.mark.parametrize(
    ("count", "box"),
    [
        # The pile of the 10⁴ balls, 25 layers deep, in a box of a fifth of the floor:
        # as deep, so as heavy on its lowest balls, and the same checks hold.
        (2000, 0.5),
        pytest.param(10_000, 1.0, marks=pytest.mark.slow),
    ],
)
def test_a_ball_pit_of_10_000_spheres_settles_without_overlaps(count, box):
    """Issue 13: 10⁴ balls dropped into a box settle with no two overlapping by more than 1 %
    of a radius, none in the floor, the pile at rest and carried by the box."""
    from visviva.demos.ball_pit import build_scene, pit_measures

    r = 0.02
    model = build_scene(count=count, radius=r, box=box, duration=1.4).build()
    simulation = vv.Simulation(model)
    simulation.run(until=1.4)
    measures = pit_measures(simulation)
    assert measures["ball_overlap_over_radius"] < 0.01
    assert measures["floor_overlap_over_radius"] < 0.01
    v = simulation.state["particle_velocity"]
    assert np.sqrt((v**2).sum(axis=1).mean()) < 0.05  # [m/s], from 5 m/s at the impact
    assert measures["box_vertical_impulse_over_weight"] == pytest.approx(1.0, abs=0.05)


def test_the_parallel_solve_gives_the_same_numbers_on_any_number_of_threads(monkeypatch):
    import visviva.collision.particle_contacts as module

    rng = np.random.default_rng(9)
    count = 6000
    x0 = rng.uniform(0.0, 0.8, (count, 3))
    x = x0 + rng.normal(0.0, 1e-3, (count, 3))
    v = rng.normal(0.0, 1.0, (count, 3))
    mass = rng.uniform(0.5, 2.0, count)
    results = []
    for threads, parallel in ((1, False), (1, True), (2, True)):
        monkeypatch.setattr(module, "PARALLEL_MIN_CONTACTS", 0 if parallel else 1 << 62)
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        try:
            xs, vs, solved = collide(mass, x, v, 0.02, e=0.7, mu=0.4, x0=x0, iterations=5)
        finally:
            numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        assert solved.slabs > 2 and solved.first.shape[0] > 1000
        results.append((xs, vs))
    for xs, vs in results[1:]:
        np.testing.assert_array_equal(xs, results[0][0])
        np.testing.assert_array_equal(vs, results[0][1])


VALID = {"restitution": 0.5, "friction": 0.2, "iterations": 10}


@pytest.mark.parametrize(
    ("field", "value", "fragment"),
    [
        ("restitution", 1.5, "less than or equal to 1"),
        ("restitution", -0.1, "greater than or equal to 0"),
        ("friction", -1.0, "greater than or equal to 0"),
        ("iterations", 0, "greater than or equal to 1"),
        ("iterations", 2.5, "valid integer"),
        ("resting_speed", -0.5, "greater than or equal to 0"),
        ("targets", ["ballz"], "no particle entity is called 'ballz'. Did you mean 'balls'?"),
    ],
)
def test_bad_collision_settings_are_refused_naming_the_entity_and_field(field, value, fragment):
    builder = vv.SceneBuilder()
    builder.add_particles([[0.0, 1.0, 0.0]], name="balls")
    settings = VALID | {field: value}
    with pytest.raises(SceneError) as error:
        if field == "targets":
            builder.add_particle_collisions(**settings)
            builder.build()
        else:
            builder.add_particle_collisions(**settings)
    message = str(error.value)
    assert "entities[1]" in message and field in message and fragment in message


def test_a_second_collision_entity_is_refused():
    builder = vv.SceneBuilder()
    builder.add_particles([[0.0, 1.0, 0.0]], name="balls")
    builder.add_particle_collisions()
    builder.add_particle_collisions(friction=0.0)
    with pytest.raises(SceneError, match=r"entities\[2\].*at most one particle_collisions"):
        builder.build()


def test_a_bad_scene_file_exits_2_from_the_cli(tmp_path, monkeypatch, capsys):
    import sys

    from visviva.cli.main import main

    scene = tmp_path / "pit.toml"
    scene.write_text(
        '[[entities]]\ntype = "particles"\npositions = [[0.0, 1.0, 0.0]]\n\n'
        '[[entities]]\ntype = "particle_collisions"\nrestitution = 2.0\n'
    )
    monkeypatch.setattr(sys, "argv", ["visviva", "run", str(scene), "-o", str(tmp_path / "o")])
    with pytest.raises(SystemExit) as exit_:
        main()
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and "Traceback" not in err
    assert "entities[1].restitution" in err


@pytest.mark.parametrize(
    ("arguments", "fragment"),
    [
        ({"inverse_mass": [1.0, -2.0]}, "`inverse_mass` of particle 1 must be finite and ≥ 0"),
        ({"inverse_mass": [[1.0]]}, "`inverse_mass` must have shape (N,)"),
        ({"inverse_mass": [1.0], "targets": [1]}, "`targets` must be a boolean mask"),
        ({"inverse_mass": [1.0], "iterations": 20_000}, "`iterations` must be at most"),
        ({"inverse_mass": [1.0], "restitution": 1.01}, "`restitution` must lie in [0, 1]"),
        ({"inverse_mass": [1.0], "friction": float("nan")}, "`friction`"),
    ],
)
def test_the_stage_refuses_bad_arguments(arguments, fragment):
    with pytest.raises(ModelError) as error:
        ParticleContacts(**arguments)
    assert fragment in str(error.value)


coordinate = st.floats(-1e6, 1e6, allow_nan=False)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    points=st.lists(st.tuples(coordinate, coordinate, coordinate), min_size=1, max_size=8),
    radius=st.floats(1e-6, 1e3),
    speed=st.floats(0.0, 1e3),
    copies=st.integers(0, 3),
)
def test_hostile_positions_and_radii_give_finite_results_and_keep_momentum(
    points, radius, speed, copies
):
    """Coincident centres, far-flung clouds, tiny and huge radii: no traceback, finite
    results, momentum kept (relative 1e-12)."""
    x = np.array(points + points[:1] * copies, dtype=float)  # some centres coincide
    rng = np.random.default_rng(len(x))
    v = rng.normal(0.0, 1.0, x.shape) * speed
    mass = rng.uniform(0.1, 10.0, len(x))
    x1, v1, _ = collide(mass, x, v, radius, e=0.5, mu=0.5)
    assert np.isfinite(x1).all() and np.isfinite(v1).all()
    p0, p1 = (mass[:, None] * v).sum(0), (mass[:, None] * v1).sum(0)
    assert np.abs(p1 - p0).max() <= 1e-12 * max((mass[:, None] * np.abs(v)).sum(), 1e-300)


def test_the_warm_start_lives_in_the_state_checkpoints_and_all():
    """Two simulations of one model do not share the remembered impulses, and a checkpoint
    restores them: the runs agree to the last bit."""
    model = scene_column(6).build()
    first, second = vv.Simulation(model), vv.Simulation(model)
    first.run(until=0.5)
    blob = first.checkpoint()
    second.run(until=0.3)  # in between, on the same stage object
    first.run(until=0.8)
    second.run(until=0.8)
    restored = vv.Simulation.restore(model, blob)
    restored.run(until=0.8)
    for other in (second, restored):
        for name in ("particle_position", "particle_velocity", "contact_normal_impulse"):
            np.testing.assert_array_equal(other.state[name], first.state[name])
    assert first.state["contact_normal_impulse"].shape[0] >= 6  # remembered contacts
