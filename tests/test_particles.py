"""Particle systems tested against physics (seeds 001–003): free fall, bounces with restitution,
Coulomb friction, resting contact, tunnelling and time of impact, emission counts and
lifetimes, checkpoints that continue bit for bit."""

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import visviva as vv

G = 9.81


def _builder(method="symplectic_euler", dt=1e-3, duration=1.0, gravity=(0.0, -G, 0.0)):
    builder = vv.SceneBuilder(name="test")
    builder.set_world(gravity=gravity)
    builder.set_integration(method=method, dt=dt, duration=duration)
    return builder


def test_free_fall_under_symplectic_euler_matches_its_exact_discrete_formula():
    """Symplectic Euler with constant g: v_n = v0 + n h g, x_n = x0 + n h v0 + h² g n(n+1)/2."""
    h, n = 1e-3, 777
    x0, v0 = np.array([0.1, 5.0, -0.2]), np.array([1.0, 2.0, 0.5])
    builder = _builder(dt=h)
    builder.add_particles([x0], velocities=[v0])
    simulation = vv.Simulation(builder.build())
    simulation.step(n)
    g = np.array([0.0, -G, 0.0])
    np.testing.assert_allclose(simulation.state["particle_velocity"][0], v0 + n * h * g, atol=1e-12)
    exact = x0 + n * h * v0 + h * h * g * n * (n + 1) / 2
    np.testing.assert_allclose(simulation.state["particle_position"][0], exact, atol=1e-12)
    assert simulation.time == n * h


def _apex_after_first_bounce(restitution: float, height: float = 1.0, radius: float = 0.05):
    h = 2e-4
    builder = _builder(dt=h, duration=3.0)
    builder.add_particles([[0.0, height + radius, 0.0]], radius=radius)
    builder.add_collider("plane", restitution=restitution)
    simulation = vv.Simulation(builder.build())
    bounced, apex = False, -math.inf
    for _ in range(30_000):
        simulation.step()
        y, vy = (
            simulation.state["particle_position"][0, 1],
            simulation.state["particle_velocity"][0, 1],
        )
        if not bounced and vy > 0.0:
            bounced = True
        elif bounced:
            apex = max(apex, y - radius)
            if vy < 0.0:
                return apex
    raise AssertionError("no apex after the first bounce")


@pytest.mark.parametrize("restitution", [0.5, 0.8, 1.0])
def test_first_rebound_reaches_e_squared_times_the_drop_height(restitution):
    """The speed after impact is e times the speed before: the apex is e² h (seed 002)."""
    apex = _apex_after_first_bounce(restitution)
    assert apex == pytest.approx(restitution**2 * 1.0, rel=0.01)


def test_sliding_particle_stops_after_v_squared_over_two_mu_g():
    """Coulomb friction decelerates a sliding particle at μ g: it stops after v²/(2 μ g)."""
    speed, mu, radius = 2.0, 0.4, 0.05
    builder = _builder(dt=1e-4, duration=2.0)
    builder.add_particles([[0.0, radius, 0.0]], velocities=[[speed, 0.0, 0.0]], radius=radius)
    builder.add_collider("plane", restitution=0.3, friction=mu)
    simulation = vv.Simulation(builder.build())
    simulation.run(until=1.0)  # it stops after v/(μ g) = 0.51 s
    distance = simulation.state["particle_position"][0, 0]
    assert distance == pytest.approx(speed**2 / (2 * mu * G), rel=0.02)
    np.testing.assert_array_equal(simulation.state["particle_velocity"][0], 0.0)


def test_resting_particle_has_zero_residual_velocity():
    """A particle lying on a floor stays there: every step gravity's push is taken back exactly
    (the contact rests below the resting speed), leaving no velocity at all."""
    radius = 0.05
    builder = _builder(dt=1e-3)
    builder.add_particles([[0.3, radius, -0.1]], radius=radius)
    builder.add_collider("plane", restitution=0.9)
    simulation = vv.Simulation(builder.build())
    simulation.step(500)
    np.testing.assert_array_equal(simulation.state["particle_velocity"][0], 0.0)
    assert simulation.state["particle_position"][0, 1] == pytest.approx(radius, abs=1e-15)


def _fast_particle_against_a_wall(time_of_impact: bool) -> np.ndarray:
    """A 100 m/s particle 0.5 m above a 1 cm thick wall, steps of 1/60 s (1.7 m each)."""
    builder = _builder(dt=1 / 60, gravity=(0.0, 0.0, 0.0))
    builder.add_particles([[0.0, 0.5, 0.0]], velocities=[[0.0, -100.0, 0.0]], radius=0.01)
    builder.add_collider("plane", thickness=0.01, restitution=1.0, time_of_impact=time_of_impact)
    simulation = vv.Simulation(builder.build())
    simulation.step(3)
    return simulation.state["particle_position"][0]


def test_time_of_impact_stops_a_fast_particle_from_tunnelling():
    assert _fast_particle_against_a_wall(True)[1] > 0.0  # bounced back
    assert _fast_particle_against_a_wall(False)[1] < -0.01  # went through the wall


def test_time_of_impact_bounces_at_the_right_time():
    """Bisection finds the impact within the step: with e = 1 and no gravity, the particle is
    back at its start after flying there and back (0.49 m each way at 100 m/s)."""
    position = _fast_particle_against_a_wall(True)
    travelled = 3 * 100.0 / 60
    # Down 0.49 m to the contact (centre at the radius), then up the rest.
    assert position[1] == pytest.approx(0.01 + (travelled - 0.49), rel=1e-6)


def test_box_sphere_and_mesh_colliders_bounce_particles_out():
    """Particles rained on a box, a sphere and a closed mesh never end inside any of them."""
    builder = _builder(dt=2e-3, duration=1.0)
    builder.add_particle_cloud(400, center=(0.0, 2.0, 0.0), size=(2.0, 0.5, 2.0), radius=0.01)
    builder.add_collider("box", center=(-0.5, 0.5, 0.0), size=(0.8, 0.4, 2.0))
    builder.add_collider("sphere", center=(0.5, 0.6, 0.0), radius=0.4)
    vertices = [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1], [0, -1, 0]]
    triangles = [[0, 2, 1], [0, 3, 2], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    builder.add_collider(
        "mesh", vertices=[[x, y + 0.2, z] for x, y, z in vertices], triangles=triangles
    )
    model = builder.build()
    simulation = vv.Simulation(model)
    simulation.run(until=1.0)
    x = simulation.state["particle_position"]
    for shape in model.stages[0].colliders.shapes:
        distance, _ = shape.signed_distance(x)
        assert distance.min() > 0.01 - 1e-6


def test_emitter_makes_rate_times_time_particles_and_each_lives_its_lifetime():
    """Births at start + k/rate: by time t there are ceil(rate t) of them; each particle dies
    at the first step end when its age reaches its lifetime."""
    rate, lifetime, h = 37.0, 0.3, 1 / 240
    builder = _builder(dt=h, gravity=(0.0, 0.0, 0.0))
    builder.add_emitter(rate=rate, speed=1.0, lifetime=lifetime, name="e")
    simulation = vv.Simulation(builder.build())
    born_at = {}
    deaths = []
    for _ in range(240):
        before = simulation.raw_state["particle_alive"].copy()
        old_age = simulation.raw_state["particle_age"].copy()
        simulation.step()
        alive = simulation.raw_state["particle_alive"]
        age = simulation.raw_state["particle_age"]
        reborn = alive & before & (age < old_age)  # died and a newborn took the slot
        for slot in np.flatnonzero((before & ~alive) | reborn):
            deaths.append(old_age[slot] + h)
            born_at.pop(slot)
        for slot in np.flatnonzero(alive & (~before | reborn)):
            born_at[slot] = simulation.time - age[slot]
    assert simulation.raw_state["emitter_serial"][0] == math.ceil(rate * simulation.time)
    assert deaths, "no particle died"
    for life in deaths:
        assert lifetime <= life < lifetime + h + 1e-12
    # Steady state: rate × lifetime particles alive at once (±1 for the phase of the clock).
    assert abs(len(simulation.state["particle_position"]) - rate * lifetime) <= 1


def test_emitter_draws_speeds_directions_and_lifetimes_within_their_ranges():
    builder = _builder(dt=0.01, gravity=(0.0, 0.0, 0.0))
    builder.add_emitter(
        bursts=[{"time": 0.0, "count": 2000}],
        shape="sphere",
        radius=0.5,
        direction=(0.0, 1.0, 0.0),
        spread_deg=30.0,
        speed=[2.0, 3.0],
        lifetime=[1.0, 2.0],
        particle_radius=[0.01, 0.02],
        seed=7,
    )
    simulation = vv.Simulation(builder.build())
    simulation.step()
    v = simulation.state["particle_velocity"]
    speed = np.linalg.norm(v, axis=1)
    assert len(v) == 2000
    assert speed.min() >= 2.0 and speed.max() <= 3.0
    angle = np.degrees(np.arccos(v[:, 1] / speed))
    assert angle.max() <= 30.0 + 1e-9
    # Uniform on the cone's cap: cos θ uniform in [cos 30°, 1] (mean and spread).
    cosine = np.cos(np.radians(angle))
    assert cosine.mean() == pytest.approx((1 + np.cos(np.radians(30))) / 2, abs=0.005)
    lifetimes = simulation.state["particle_lifetime"]
    assert lifetimes.min() >= 1.0 and lifetimes.max() <= 2.0
    assert lifetimes.mean() == pytest.approx(1.5, abs=4 * 0.29 / math.sqrt(2000))
    # Positions inside the sphere, drifted by the step's flight since the burst.
    x = simulation.state["particle_position"] - 0.01 * v
    assert np.linalg.norm(x, axis=1).max() <= 0.5 + 1e-12


def _fountain() -> vv.Model:
    builder = _builder(dt=1 / 240, duration=2.0)
    builder.add_emitter(
        rate=300,
        speed=[3.0, 4.0],
        spread_deg=15,
        lifetime=[0.8, 1.2],
        seed=3,
        size_ramp=[[0.0, 1.0], [1.0, 0.2]],
        name="fountain",
    )
    builder.add_particles([[0.3, 1.0, 0.0]], velocities=[[0.0, 0.0, 1.0]], name="ball")
    builder.add_force("drag", coefficient=0.001)
    builder.add_force("vortex", circulation=2.0, coefficient=0.0005, targets=["fountain"])
    builder.add_collider("plane", restitution=0.4, friction=0.2)
    builder.add_collider("sphere", center=(0.0, 0.8, 0.5), radius=0.3, restitution=0.7)
    return builder.build()


def test_checkpoint_and_restore_continue_bit_for_bit():
    model = _fountain()
    whole = vv.Simulation(model)
    whole.step(317)
    split = vv.Simulation(model)
    split.step(123)
    blob = split.checkpoint()
    resumed = vv.Simulation.restore(model, blob)
    resumed.step(194)
    assert resumed.time == whole.time
    for name in whole.raw_state.names():
        np.testing.assert_array_equal(resumed.raw_state[name], whole.raw_state[name], err_msg=name)


def test_run_until_lands_exactly_and_continues_on_the_same_grid():
    model = _fountain()
    one = vv.Simulation(model)
    one.run(until=0.5)
    pieces = vv.Simulation(model)
    pieces.run(until=0.25)
    pieces.run(until=0.5)
    assert pieces.time == one.time == 0.5
    np.testing.assert_array_equal(pieces.raw_state.parts[0], one.raw_state.parts[0])
    off_grid = vv.Simulation(model)
    off_grid.run(until=0.1234)
    assert off_grid.time == 0.1234


def test_restore_refuses_another_scene_or_bytes_that_are_not_a_checkpoint():
    blob = vv.Simulation(_fountain()).checkpoint()
    other = _builder()
    other.add_particles([[0.0, 1.0, 0.0]])
    with pytest.raises(vv.ModelError, match="another scene"):
        vv.Simulation.restore(other.build(), blob)
    with pytest.raises(vv.ModelError, match="not a visviva checkpoint"):
        vv.Simulation.restore(_fountain(), b"not a checkpoint")


def test_state_shows_live_particles_only_in_slot_order():
    simulation = vv.Simulation(_fountain())
    simulation.run(until=0.5)
    raw = simulation.raw_state
    alive = raw["particle_alive"]
    np.testing.assert_array_equal(
        simulation.state["particle_position"], raw["particle_position"][alive]
    )
    assert simulation.state["particle_position"].shape == (alive.sum(), 3)
    with pytest.raises(ValueError):
        simulation.state["particle_position"][0, 0] = 1.0  # a read-only copy


def test_energy_of_a_bouncing_elastic_particle_is_kept():
    """e = 1 with time of impact: the energy after many bounces is the energy before, to the
    order of the integrator (symplectic Euler: O(h))."""
    builder = _builder(dt=1e-4, duration=3.0)
    builder.add_particles([[0.0, 1.0, 0.0]], radius=0.05, mass=2.0)
    builder.add_collider("plane", restitution=1.0)
    simulation = vv.Simulation(builder.build())
    start = simulation.energy()
    simulation.run(until=2.0)  # several bounces
    assert simulation.energy() == pytest.approx(start, rel=2e-3)


@pytest.mark.parametrize("dt", [0.01, 0.001])
def test_static_friction_holds_a_particle_on_a_slope(dt):
    """On a 30° slope with μ = 1 > tan 30°, friction holds the particle where it is: no creep
    of h² g sin θ a step, and zero velocity."""
    angle = math.radians(30.0)
    normal = (-math.sin(angle), math.cos(angle), 0.0)
    radius = 0.05
    start = [radius * normal[0], radius * normal[1], 0.0]
    builder = _builder(dt=dt, duration=2.0)
    builder.add_particles([start], radius=radius)
    builder.add_collider("plane", normal=normal, friction=1.0, restitution=0.0)
    simulation = vv.Simulation(builder.build())
    simulation.run(until=1.0)
    np.testing.assert_allclose(simulation.state["particle_position"][0], start, atol=1e-15)
    np.testing.assert_array_equal(simulation.state["particle_velocity"][0], 0.0)


def test_births_beyond_the_capacity_are_dropped_and_counted_without_memory():
    """A rate of 10¹² per second into 100 slots: 100 born, the rest counted, nothing allocated
    for them."""
    builder = _builder(dt=0.01, duration=0.1)
    builder.add_emitter(rate=1e12, capacity=100)
    simulation = vv.Simulation(builder.build())
    simulation.step()
    assert simulation.raw_state["particle_alive"].sum() == 100
    assert simulation.raw_state["emitter_dropped"][0] == 1e12 * 0.01 - 100


@pytest.mark.parametrize(
    "emitter",
    [
        {"rate": 2.0**62},
        {"rate": 1.0e9, "lifetime": 1.0e3},
        {"rate": 1.0, "direction": (1e200, 0, 0)},
    ],
)
def test_emitters_too_large_to_allocate_or_count_are_refused_before_allocation(emitter):
    builder = _builder()
    builder.add_emitter(**emitter)
    if "direction" in emitter:  # a huge but valid direction is just a direction
        assert builder.build().emitters[0].direction.tolist() == [1.0, 0.0, 0.0]
        return
    with pytest.raises(vv.SceneError, match=r"entities\[0\]"):
        builder.build()


@settings(max_examples=200, deadline=None)
@given(
    alive=st.lists(st.booleans(), min_size=1, max_size=80),
    start=st.integers(0, 80),
    stop=st.integers(0, 80),
    count=st.integers(0, 20),
)
@example(alive=[True] * 40 + [False, True, False] + [True] * 20, start=3, stop=70, count=3)
@example(alive=[True] * 16 + [False] * 3, start=0, stop=19, count=2)
def test_free_slots_are_the_lowest_free_ones(alive, start, stop, count):
    """The free-slot scan (which skips eight live slots at a time) finds what a plain scan
    finds: the lowest ``count`` free slots in ``[start, stop)``."""
    from visviva.particles.emission import _free_slots

    flags = np.array(alive, dtype=np.bool_)
    start, stop = min(start, flags.shape[0]), min(stop, flags.shape[0])
    words = flags[: flags.shape[0] // 8 * 8].view(np.uint64)
    expected = [i for i in range(start, stop) if not flags[i]][:count]
    assert _free_slots(flags, words, start, stop, count).tolist() == expected
