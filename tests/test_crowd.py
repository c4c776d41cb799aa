"""Crowds (social-force model): the drive's closed form, Newton's third law, a brute-force
reference, evacuations through doors, exits, and refusals of bad scenes."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import visviva as vv
from visviva.analysis.crowds import exit_flow, exited, mean_flow
from visviva.cli.main import main
from visviva.demos.crowd import evacuate, room
from visviva.errors import SceneError
from visviva.ode.workspace import Workspace
from visviva.particles.crowd import REACH, Crowd

H = 0.01  # [s]
TAU = 0.5  # [s]
V0 = 1.34  # [m/s]


def _crowd_stage(model: vv.model.Model) -> Crowd:
    return next(s for s in model.stages if isinstance(s, Crowd))


def _walker(dt: float, duration: float) -> vv.SceneBuilder:
    builder = vv.SceneBuilder(name="walker")
    builder.set_integration(dt=dt, duration=duration)
    builder.add_particles(name="people", positions=[[0.0, 1.0, 0.0]], mass=80.0, radius=0.3)
    builder.add_crowd(["people"], goal=(1000.0, 1.0, 0.0), relaxation_time=TAU)
    return builder


def _speed_error(dt: float) -> float:
    """Largest |v(t) − v⁰(1 − e^(−t/τ))| over 5τ of a lone agent starting at rest."""
    simulation = vv.Simulation(_walker(dt, 5 * TAU).build())
    recording = simulation.record(until=5 * TAU, record_every=1)
    t, v = recording.time, recording["particle_velocity"][:, 0, :]
    assert np.all(v[:, 1] == 0.0) and np.all(v[:, 2] == 0.0)  # straight along x, no fall
    assert np.all(recording["particle_position"][:, 0, 1] == 1.0)  # the height is kept
    return float(np.abs(v[:, 0] - V0 * (1.0 - np.exp(-t / TAU))).max())


def test_a_lone_agent_relaxes_to_its_preferred_speed_as_the_closed_form():
    """m dv/dt = m (v⁰ − v)/τ from rest: v = v⁰(1 − e^(−t/τ)). The stage's forward-Euler kick
    gives v_n = v⁰(1 − (1 − h/τ)ⁿ), within v⁰ (h/τ)(t/2τ) e^(−t/τ) ≤ v⁰ h/(2eτ) of it: first
    order, so halving h halves the error."""
    coarse, fine = _speed_error(H), _speed_error(H / 2)
    assert coarse <= V0 * H / (2 * math.e * TAU) * 1.05
    assert 1.9 < coarse / fine < 2.1


#: Two agents overlapping by 0.07 m.
PRESSED = np.array([[0.0, 1.0, 0.0], [0.45, 1.0, 0.2]])
SLIDING = np.array([[0.7, 0.0, -0.2], [-0.4, 0.0, 0.9]])


def _pair_model(**crowd) -> vv.model.Model:
    """Two agents (radii 0.3 and 0.26 m, 80 and 60 kg), built apart."""
    builder = vv.SceneBuilder(name="pair")
    builder.set_integration(dt=H, duration=1.0)
    builder.add_particles(
        name="people",
        positions=[[0.0, 1.0, 0.0], [3.0, 1.0, 0.0]],
        radius=[0.3, 0.26],
        mass=[80.0, 60.0],
    )
    builder.add_crowd(["people"], goal=(5.0, 1.0, 0.0), **crowd)
    return builder.build()


def _pair() -> tuple[Crowd, np.ndarray, np.ndarray]:
    return _crowd_stage(_pair_model()), PRESSED.copy(), SLIDING.copy()


def test_two_agents_pressed_together_push_each_other_equally_and_oppositely():
    """Repulsion, body force and sliding friction (Helbing et al. 2000) are antisymmetric in
    i, j to the last bit: the sums of the pair's forces and of its momentum change are zero."""
    stage, x, v = _pair()
    _, agents, _ = stage.forces(x, v)
    assert np.abs(agents[0]).max() > 1e3  # overlapping by 0.07 m: body force and friction act
    np.testing.assert_array_equal(agents[0], -agents[1])
    # One step of the stage: the pair's momentum changes by h × (sum of the drives) only.
    model = _pair_model(max_speed=100.0)
    stage = _crowd_stage(model)
    start = vv.Simulation(model).raw_state
    state = start.from_parts(0.0, (PRESSED.ravel(), SLIDING.ravel()))
    after = stage.apply(state, state, H, Workspace())
    drive, agents, _ = stage.forces(state["particle_position"], state["particle_velocity"])
    mass = model.particle_mass[:, None]
    change = (mass * (after["particle_velocity"] - state["particle_velocity"])).sum(axis=0)
    impulse = H * np.abs(agents).max()
    assert impulse > 10.0  # N·s: the interaction's impulse on each of them
    np.testing.assert_allclose(change, H * drive.sum(axis=0), rtol=0, atol=1e-14 * impulse)


def _share(rate: np.ndarray, h: float) -> np.ndarray:
    """φ(hλ) = (1 − e^(−hλ))/(hλ): the sliding friction of a step of h integrated exactly."""
    z = h * rate
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(z < 1e-12, 1.0, -np.expm1(-z) / z)


def _brute_force(
    stage: Crowd, x: np.ndarray, v: np.ndarray, h: float = 0.0
) -> tuple[np.ndarray, ...]:
    """The same three forces in plain NumPy over every pair and wall (no grid), the sliding
    friction as a step of ``h`` applies it (0: the papers' force)."""
    a = stage.agents
    p, u = x[a][:, [0, 2]], v[a][:, [0, 2]]
    c = stage.crowd
    A, B, k, kappa, v0, tau, cut = stage.params[c].T
    m, r = stage.mass, stage.radius
    goal = np.where(stage.has_goal[c][:, None], stage.goal[c], np.nan)
    to_goal = goal - p
    e = to_goal / np.linalg.norm(to_goal, axis=1)[:, None]
    drive = m[:, None] * (v0[:, None] * e - u) / tau[:, None]
    diff = p[:, None, :] - p[None, :, :]
    d = np.sqrt((diff**2).sum(axis=2))
    rij = r[:, None] + r[None, :]
    near = (d**2 <= (rij + cut[:, None]) ** 2) & ~np.eye(len(a), dtype=bool)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = diff / d[..., None]
    overlap = rij - d
    g = np.maximum(overlap, 0.0)
    push = A[:, None] * np.exp(overlap / B[:, None]) + 0.5 * (k[:, None] + k[None, :]) * g
    t = np.stack([-n[..., 1], n[..., 0]], axis=2)
    damper = 0.5 * (kappa[:, None] + kappa[None, :]) * g
    damper = damper * _share(damper * (1.0 / m[:, None] + 1.0 / m[None, :]), h)
    slide = damper * ((u[None, :] - u[:, None]) * t).sum(2)
    pair = push[..., None] * n + slide[..., None] * t
    social = np.where(near[..., None], pair, 0.0).sum(axis=1)
    walls = np.zeros_like(social)
    for w, shape in enumerate(stage.walls.shapes):
        dist, normal = shape.signed_distance(x[a])
        mine = (stage.wall_mask[c] >> np.uint64(w)) & np.uint64(1) == 1
        nw = normal[:, [0, 2]]
        over = r - dist
        gw = np.maximum(over, 0.0)
        tw = np.stack([-nw[:, 1], nw[:, 0]], axis=1)
        force = (A * np.exp(over / B) + k * gw)[:, None] * nw
        damper = kappa * gw * _share(kappa * gw / m, h)
        force -= (damper * (u * tw).sum(axis=1))[:, None] * tw
        walls += np.where((mine & (over >= -cut))[:, None], force, 0.0)
    return drive, social, walls


def _dense_scene() -> vv.model.Model:
    """300 agents of two crowds (built on a lattice 0.75 m apart) by two walls."""
    rng = np.random.default_rng(7)
    builder = vv.SceneBuilder(name="dense")
    builder.set_integration(dt=H, duration=1.0)
    lattice = np.stack(np.meshgrid(np.arange(20), np.arange(15)), axis=-1).reshape(-1, 2)
    positions = np.column_stack(
        [0.6 + 0.75 * lattice[:, 0], np.full(300, 1.0), -4.3 + 0.75 * lattice[:, 1]]
    )
    radius = rng.uniform(0.25, 0.35, 300)
    for name, rows in (("calm", slice(0, 150)), ("hurried", slice(150, 300))):
        builder.add_particles(
            name=name, positions=positions[rows], radius=radius[rows].tolist(), mass=80.0
        )
    builder.add_collider("box", center=(-0.1, 1.0, 0.0), size=(0.2, 2.0, 9.0), name="back")
    builder.add_collider("plane", point=(0.0, 0.0, -4.7), normal=(0.0, 0.0, 1.0), thickness=0.2)
    builder.add_crowd(["calm"], goal=(20.0, 1.0, 1.0))
    builder.add_crowd(
        ["hurried"], goal=(-20.0, 1.0, 3.0), preferred_speed=3.0, repulsion=2500.0,
        repulsion_range=0.1, body_stiffness=2e5, friction=1e5, walls=["back"],
    )  # fmt: skip
    return builder.build()


@pytest.mark.parametrize("h", [0.0, 0.005, 1.0])
def test_kernel_forces_equal_a_brute_force_numpy_sum_on_300_agents(h):
    """At h = 0 the papers' forces; at h > 0 the sliding friction a step applies."""
    model = _dense_scene()
    stage = _crowd_stage(model)
    rng = np.random.default_rng(8)
    # Packed in a 9 m × 9 m yard, many touching, three pressed into the walls.
    x = np.column_stack([rng.uniform(0.6, 9.4, 300), np.ones(300), rng.uniform(-4.3, 4.4, 300)])
    x[0, 0], x[1, 2], x[200, 0] = 0.2, -4.45, 0.25
    v = rng.normal(0.0, 1.0, x.shape)
    found = stage.forces(x, v, h=h)
    expected = _brute_force(stage, x, v, h)
    assert np.abs(found[1]).max() > 1e4  # agents overlap: every term is exercised
    assert np.abs(found[2]).max() > 0.0
    for got, want in zip(found, expected, strict=True):
        scale = np.abs(want).max()
        np.testing.assert_allclose(got[stage.agents][:, [0, 2]], want, rtol=0, atol=1e-12 * scale)
        assert np.all(got[:, 1] == 0.0)


@pytest.mark.parametrize("overlap", [0.02, 0.2, 0.5])
def test_a_step_of_sliding_friction_decays_the_sliding_exactly_and_never_reverses_it(overlap):
    """For a pair alone, du/dt = −λ u with λ = κ g (1/m_i + 1/m_j) for the relative sliding u:
    a step of h leaves u e^(−hλ) (explicit Euler would leave u (1 − hλ): reversed beyond
    hλ = 1, which g = 0.2 m reaches 12 times over at h = 0.01 s)."""
    stage = _crowd_stage(_pair_model())
    x = np.array([[0.0, 1.0, 0.0], [0.56 - overlap, 1.0, 0.0]])  # r_ij = 0.56 m, along x
    v = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]])  # u = (v_j − v_i)·t = 2 m/s along z
    _, agents, _ = stage.forces(x, v, h=H)
    mass = np.array([80.0, 60.0])
    # Friction is along t = ±z; the push along x does not touch the sliding.
    u_after = 2.0 + H * (agents[1, 2] / mass[1] - agents[0, 2] / mass[0])
    rate = 2.4e5 * overlap * (1 / 80 + 1 / 60)
    np.testing.assert_allclose(u_after, 2.0 * np.exp(-H * rate), rtol=1e-12, atol=1e-15)
    assert u_after >= 0.0


def test_agents_placed_at_random_on_top_of_each_other_untangle_and_walk_to_the_goal():
    """80 agents dropped at random in a 4 m square (pairs overlapping by up to a body): the
    body force spreads them and the friction, integrated over each step, only damps their
    sliding; within 8 s they walk to the goal together (no pair left spinning at full speed,
    as an explicit friction did)."""
    builder = vv.SceneBuilder(name="heap")
    builder.set_integration(dt=H, duration=8.0)
    builder.add_particle_cloud(
        80, center=(0.0, 1.0, 0.0), size=(4.0, 1e-3, 4.0), mass=80.0, radius=0.3, name="heap"
    )
    builder.add_crowd(["heap"], goal=(100.0, 1.0, 0.0))
    simulation = vv.Simulation(builder.build())
    start = simulation.state["particle_position"]
    gaps = np.linalg.norm(start[:, None, [0, 2]] - start[None, :, [0, 2]], axis=2)
    assert np.min(gaps + np.eye(80) * 9) < 0.3  # some start more than half a body into another
    simulation.run(until=8.0)
    v = simulation.state["particle_velocity"]
    assert np.all(v[:, 0] > 0.5 * V0)  # every one heads for the goal (+x) ...
    assert np.all(np.abs(v[:, 2]) < 0.5 * V0)  # ... none circling


def test_dead_agents_are_nobodys_neighbours_and_feel_nothing():
    stage, x, v = _pair()
    alive = np.array([True, False])
    drive, agents, _ = stage.forces(x, v, alive)
    assert np.all(agents == 0.0)  # the dead one overlaps the live one by 0.07 m
    assert np.all(drive[1] == 0.0) and np.any(drive[0] != 0.0)


def _room_model(door: float, agents: int = 40, side: float = 6.0, duration: float = 120.0):
    builder = vv.SceneBuilder(name="room")
    builder.set_integration(dt=H / 2, duration=duration)  # jams at the door: overlaps of cm
    room(builder, agents=agents, side=side, door=door, seed=3)
    return builder.build()


def test_everyone_leaves_a_room_and_nobody_ends_in_a_wall():
    model = _room_model(1.2)
    stage = _crowd_stage(model)
    simulation = vv.Simulation(model)
    deepest = [-math.inf]
    radius = model.particle_radius

    def watch(state, energy):
        live = state["particle_alive"]
        x = state["particle_position"][live]
        for shape in stage.walls.shapes:
            distance, _ = shape.signed_distance(x)
            deepest[0] = max(deepest[0], float((radius[live] - distance).max(initial=-math.inf)))
            assert distance.min(initial=math.inf) > 0.0  # no centre inside a wall

    simulation.run(90.0, record_every=1, on_frame=watch)
    state = simulation.raw_state
    assert not state["particle_alive"].any()
    times = state["crowd_exit_time"]
    assert np.isfinite(times).all() and times.max() < 90.0
    assert np.all(state["particle_position"] == 0.0) and np.all(state["particle_velocity"] == 0.0)
    assert deepest[0] < 0.05  # overlaps with the walls (if any) of centimetres at most
    assert exited(times, [times.max()])[0] == 40
    centres, flow = exit_flow(times, 1.0)
    assert flow.sum() * 1.0 == 40 and centres[-1] > times.max() - 1.0


def test_the_flow_through_a_door_grows_with_its_width():
    flows = []
    for door in (1.1, 1.5, 2.0):
        simulation = vv.Simulation(_room_model(door, agents=50, side=7.0))
        evacuate(simulation, 120.0)
        times = simulation.raw_state["crowd_exit_time"]
        assert np.isfinite(times).all()
        flows.append(mean_flow(times))
    assert flows[0] < flows[1] < flows[2], flows
    assert flows[0] > 0.5 and flows[2] < 6.0  # agents/s: of the order of 1.3 per metre of door


def test_an_agent_entering_an_exit_leaves_at_that_step():
    builder = vv.SceneBuilder(name="exit")
    builder.set_integration(dt=H, duration=2.0)
    builder.add_particles(
        name="people", positions=[[0.0, 1.0, 0.0]], velocities=[[1.0, 0, 0]], mass=80.0
    )
    builder.add_crowd(["people"], exits=[{"center": (1.5, 1.0, 0.0), "size": (1.0, 1.0, 1.0)}])
    simulation = vv.Simulation(builder.build())
    steps = 0
    while simulation.raw_state["particle_alive"][0]:
        x = simulation.raw_state["particle_position"][0, 0]
        simulation.step()
        steps += 1
    assert x < 1.0  # it left in the step that carried it past x = 1
    assert simulation.raw_state["crowd_exit_time"][0] == pytest.approx(steps * H, abs=1e-12)
    assert simulation.state["particle_position"].shape == (0, 3)  # hidden from views


def _bad(builder_steps, match: str) -> None:
    builder = vv.SceneBuilder(name="bad")
    builder.set_integration(dt=H, duration=1.0)
    with pytest.raises(SceneError, match=match):
        builder_steps(builder)
        builder.build()


def _people(builder, positions=((1.0, 1.0, 0.0), (2.0, 1.0, 0.0)), **fields):
    builder.add_particles(
        name="people", positions=[list(p) for p in positions], radius=0.3, mass=80.0, **fields
    )


def _wall(builder):
    builder.add_collider("box", center=(3.0, 1.0, 0.0), size=(0.2, 2.0, 4.0), name="wall")


EXIT = {"center": (5.0, 1.0, 0.0), "size": (1.0, 2.0, 1.0)}


@pytest.mark.parametrize(
    ("steps", "match"),
    [
        (lambda b: b.add_particles(name="people", positions=[[0, 1, 0]], radius=0.0),
         r"entities\[0\]\.radius.*greater than 0"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[EXIT], repulsion=-1.0)),
         r"entities\[1\]\.repulsion.*greater than or equal to 0"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[EXIT], friction=-2.0)),
         r"entities\[1\]\.friction"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[EXIT], preferred_speed=0.0)),
         r"entities\[1\]\.preferred_speed.*greater than 0"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[EXIT], relaxation_time=-0.5)),
         r"entities\[1\]\.relaxation_time.*greater than 0"),
        (lambda b: (_people(b), b.add_crowd(["people"])), r"needs a `goal` or at least one"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[{**EXIT, "size": (1.0, 0.0, 1.0)}])),
         r"entities\[1\]\.exits\[0\]\.size"),
        (lambda b: (_people(b), _wall(b), b.add_crowd(["people"], goal=(3.0, 0.0, 1.0))),
         r"entities\[2\]\.goal: the goal .* lies inside the wall 'wall'"),
        (lambda b: (_people(b), _wall(b),
                    b.add_crowd(["people"], exits=[{**EXIT, "center": (3.0, 1.0, 0.5)}])),
         r"entities\[2\]\.exits\[0\]: the exit's centre .* inside the wall 'wall'"),
        (lambda b: (_people(b, ((1.0, 1.0, 0.0), (2.8, 1.0, 1.0))), _wall(b),
                    b.add_crowd(["people"], exits=[EXIT])),
         r"entities\[0\]: agent 1 of 'people' overlaps the wall 'wall'"),
        (lambda b: (_people(b, ((1.0, 1.0, 0.0), (2.0, 3.5, 0.0))),
                    b.add_crowd(["people"], exits=[EXIT])),
         r"agent 1 of 'people' stands at height y = 3.5 m, outside"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[EXIT], walls=["wal"])),
         r"walls\[0\]: no collider is called 'wal'"),
        (lambda b: (_people(b), _wall(b), b.add_crowd(["people"], exits=[EXIT], walls=["wal"])),
         r"Did you mean 'wall'\?"),
        (lambda b: (_people(b), b.add_crowd(["peple"], exits=[EXIT])),
         r"targets\[0\]: no particle entity is called 'peple'"),
        (lambda b: (b.add_emitter(rate=1.0, name="spray"), b.add_crowd(["spray"], exits=[EXIT])),
         r"'spray' is of type emitter"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[EXIT]),
                    b.add_crowd(["people"], exits=[EXIT])),
         r"already walk in crowd"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[EXIT], relaxation_time=0.01)),
         r"relaxation_time: the step h = 0.01 s must be shorter"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[EXIT], body_stiffness=1e8)),
         r"body_stiffness: the step h = 0.01 s must be below 2/sqrt\(2k/m\)"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[EXIT], repulsion_range=1e-4)),
         r"repulsion_range: the repulsion at full overlap"),
        (lambda b: (_people(b), b.add_crowd(["people"], exits=[EXIT], max_speed=1.0)),
         r"`max_speed` \(1.0 m/s\) must be at least `preferred_speed`"),
    ],
    ids=[
        "radius", "negative-repulsion", "negative-friction", "speed", "tau", "no-goal",
        "flat-exit", "goal-in-wall", "exit-in-wall", "agent-in-wall", "stranded-agent",
        "unknown-wall", "misspelt-wall", "unknown-target", "emitter-target", "two-crowds",
        "step-vs-tau", "step-vs-k", "tiny-range", "max-speed",
    ],
)  # fmt: skip
def test_bad_crowds_are_refused_naming_entity_and_field(steps, match):
    _bad(steps, match)


def test_the_command_line_refuses_a_crowd_in_a_wall_with_exit_status_2(
    monkeypatch, capsys, tmp_path
):
    scene = tmp_path / "crowd.toml"
    scene.write_text(
        """
[integration]
dt = 0.01
duration = 1.0

[[entities]]
type = "particles"
name = "people"
positions = [[1.0, 1.0, 0.0]]
radius = 0.3
mass = 80.0

[[entities]]
type = "collider"
name = "wall"
shape = "box"
center = [1.2, 1.0, 0.0]
size = [0.2, 2.0, 4.0]

[[entities]]
type = "crowd"
targets = ["people"]
goal = [5.0, 1.0, 0.0]
"""
    )
    monkeypatch.setattr(sys, "argv", ["visviva", "run", str(scene), "-o", str(tmp_path / "o")])
    with pytest.raises(SystemExit) as exit_:
        main()
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and "Traceback" not in err
    assert "entities[0]" in err and "agent 0 of 'people' overlaps the wall 'wall'" in err


coordinate = st.one_of(
    st.floats(-10.0, 10.0),
    st.sampled_from([0.0, 2.9, 3.0, 3.1, 1e6, -1e12, 1e15, 1e100, -1e160, 1e300]),
)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    points=st.lists(st.tuples(coordinate, st.sampled_from([1.0, 0.0, 1e200]), coordinate),
                    min_size=1, max_size=8),
    duplicate=st.booleans(),
)  # fmt: skip
def test_hostile_positions_give_a_clear_refusal_or_a_finite_run(points, duplicate):
    """Agents anywhere (far away, in or on the wall, on top of each other): the build refuses
    with a SceneError, or a short run stays finite with every live agent at its height."""
    if duplicate:
        points = [*points, points[0]]
    builder = vv.SceneBuilder(name="hostile")
    builder.set_integration(dt=H, duration=0.2)
    builder.add_particles(name="people", positions=[list(p) for p in points], radius=0.3, mass=80.0)
    _wall(builder)
    builder.add_crowd(["people"], goal=(6.0, 1.0, 0.0))
    try:
        model = builder.build()
    except SceneError as error:
        assert str(error).strip()
        return
    simulation = vv.Simulation(model)
    simulation.run(0.2)
    state = simulation.raw_state
    assert np.isfinite(state["particle_position"]).all()
    assert np.isfinite(state["particle_velocity"]).all()
    speed = np.hypot(state["particle_velocity"][:, 0], state["particle_velocity"][:, 2])
    assert speed.max() <= 1.3 * 1.34 * (1 + 1e-12)
    np.testing.assert_array_equal(state["particle_position"][:, 1], np.array(points)[:, 1])


def test_reach_of_the_repulsion_is_the_stated_cut():
    """The repulsion is cut where A exp(−s/B) = CUTOFF · A: s = B ln(1/CUTOFF) beyond contact."""
    stage = _crowd_stage(_pair_model())
    assert math.log(1e3) == pytest.approx(REACH)
    gap = stage.params[0, 6]
    x = np.array([[0.0, 1.0, 0.0], [0.56 + gap * (1 - 1e-9), 1.0, 0.0]])
    _, near, _ = stage.forces(x, np.zeros((2, 3)))
    assert near[0, 0] == pytest.approx(-2000.0 * 1e-3, rel=1e-6)
    x[1, 0] = 0.56 + gap * (1 + 1e-9)
    _, far, _ = stage.forces(x, np.zeros((2, 3)))
    assert np.all(far == 0.0)
